#pragma once
// navd's default mode (no --replay, no sensor with a device): the dive of the config's `sim`
// section (config/README.md) is simulated with nav::sim::simulate_dive when it is missing (or
// was simulated with another seed, image count or outlier rate, per its sim.json), then
// replayed through navd's replay mode (replay_mode.h) at the configured speed, published on
// LCM, and with --out the replay outputs and the report (metrics.json, figures) are written.
// A second run reuses the cached dive. Progress goes to stderr every 10 %; SIGTERM/SIGINT
// during the simulation stop it (the partial dive has no sim.json and is not reused).

#include <csignal>
#include <optional>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/daemon/system/sd_notify.h"

namespace nav::navd {

/// The dive log of config.sim (simulated first when missing); nullopt when a stop signal came
/// during the simulation. Throws std::runtime_error / std::invalid_argument on failure.
std::optional<std::string> ensure_sim_dive(const daemon::SimDiveConfig& sim,
                                           const std::string& config_path,
                                           const sigset_t& stop_signals,
                                           const daemon::SdNotifier& notifier);

/// The checkpoint input identity of the default mode's dive: "sim <absolute dive_dir> seed S
/// images N outlier_rate R" (a dive simulated again with other options is another input).
std::string sim_dive_identity(const daemon::SimDiveConfig& sim);

}  // namespace nav::navd
