#pragma once
// `navtool survey`'s dive: the dive of the config's `sim` section (config/README.md), simulated
// with nav::sim::simulate_dive into `sim.dive_dir` when it is missing or was simulated with another
// seed, image count or outlier rate (per its sim.json), or without frames when they are asked for
// (`render_images`: images/NNNNNN.png for navd's vision stage); otherwise the cached dive is reused
// (a dive with frames serves a run without them too). Progress goes to stderr every 10 %;
// SIGTERM/SIGINT during the simulation stop it (the partial dive has no sim.json and is never
// reused). The caller replays the dive through navd's replay runner
// (nav/daemon/service/replay_mode.h) and writes the report.

#include <csignal>
#include <optional>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/daemon/system/sd_notify.h"

namespace nav::tool {

/// The dive log of config.sim (simulated first when missing, with rendered frames when
/// `render_images`); nullopt when a stop signal came during the simulation. Throws
/// std::runtime_error / std::invalid_argument on failure.
std::optional<std::string> ensure_sim_dive(const daemon::SimDiveConfig& sim, bool render_images,
                                           const std::string& config_path,
                                           const sigset_t& stop_signals,
                                           const daemon::SdNotifier& notifier);

/// The checkpoint input identity of the survey dive: "sim <absolute dive_dir> seed S
/// images N outlier_rate R" (a dive simulated again with other options is another input).
std::string sim_dive_identity(const daemon::SimDiveConfig& sim);

}  // namespace nav::tool
