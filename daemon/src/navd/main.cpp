// navd: the navigation daemon. One filter path in every mode: a source -> MeasurementQueue ->
// time ordering -> NavFilter (view-based SLAM, ESDF) -> LCM publishers.
//   navd --config VEHICLE.yaml [--checkpoints] [--duration-s S]
//        a sensor has a hardware transport: the device threads are the source (live_mode.h)
//   navd --config C --replay DIVE.lcmlog [--speed X | --as-fast-as-possible] [--out DIR]
//        [--checkpoints]: the dive log is the source (replay_mode.h)
//   navd --config config/sim.yaml [--images N] [--seed S] [--speed X | --as-fast-as-possible]
//        [--out DIR] [--checkpoints]: the default mode: the config's `sim` dive, simulated when
//        missing (sim_dive.h), replayed as with --replay; with --out also the report. LCM falls
//        back to memq:// with a warning when the config's udpm cannot be opened (lcm_url.h)
// SIGTERM/SIGINT stop every mode within a second (STOPPING=1), exit 0.
// Exit status: 0 done or stopped, 1 the filter, simulation or report failed, 2 bad arguments or
// configuration.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <optional>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/daemon/system/sd_notify.h"
#include "navd/lcm_url.h"
#include "navd/live_mode.h"
#include "navd/replay_mode.h"
#include "navd/sim_dive.h"

namespace {

using namespace nav;

struct Args {
  std::string config_path;
  std::optional<int> images;            ///< overrides sim.images
  std::optional<std::int64_t> seed;     ///< overrides sim.seed
  double speed = 1.0;
  bool as_fast_as_possible = false;
  std::string lcm_url;
  double duration_s = 0.0;   ///< live mode: 0 until a signal
  std::string replay;        ///< a dive log to replay
  std::string out_dir;       ///< replay output directory (replay and default modes)
  bool checkpoints = false;  ///< every mode: resume from / write checkpoints
};

void add_options(CLI::App& app, Args& args) {
  app.add_option("--config", args.config_path, "navd YAML configuration")->required();
  app.add_option("--images", args.images, "default mode: images in the simulated dive (sim.images)")
      ->check(CLI::Range(2, 100000));
  app.add_option("--seed", args.seed, "default mode: seed of the simulated dive (sim.seed)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{2147483647}));
  auto* speed = app.add_option("--speed", args.speed, "replay speed, x real time")
                    ->check(CLI::PositiveNumber);
  app.add_flag("--as-fast-as-possible", args.as_fast_as_possible, "replay without pacing")
      ->excludes(speed);
  app.add_option("--lcm-url", args.lcm_url, "LCM URL (overrides lcm.url)");
  app.add_option("--replay", args.replay, "replay this dive log (hil-tests/README.md)")
      ->check(CLI::ExistingFile);
  app.add_option("--out", args.out_dir,
                 "replay and default modes: write the replay output directory (default mode: "
                 "and the report)");
  app.add_flag("--checkpoints", args.checkpoints,
               "every mode: resume from the newest valid checkpoint of this input (the replayed "
               "log, the simulated dive, or 'live') in checkpoint.path and write checkpoints "
               "there (period_s, at the end)");
  app.add_option("--duration-s", args.duration_s,
                 "live mode: stop after this many seconds (0: no limit)")
      ->check(CLI::NonNegativeNumber);
}

/// Blocks SIGTERM/SIGINT in every thread (threads inherit the mask); the modes wait for them.
sigset_t block_stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return set;
}

int run_default_mode(daemon::NavdConfig config, const Args& args, const sigset_t& signals,
                     const daemon::SdNotifier& notifier) {
  // udpm (config/sim.yaml) on a host without a multicast route: memq with a warning, unless the
  // URL was asked for with --lcm-url (lcm_url.h).
  config.lcm.url = navd::usable_lcm_url(config.lcm.url, args.lcm_url.empty());
  daemon::SimDiveConfig sim = *config.sim;
  if (args.images) sim.images = *args.images;
  if (args.seed) sim.seed = static_cast<int>(*args.seed);
  const std::optional<std::string> log =
      navd::ensure_sim_dive(sim, args.config_path, signals, notifier);
  if (!log) return 0;  // stopped during the simulation
  const navd::ReplayModeArgs replay{
      *log,         args.config_path, args.speed, args.as_fast_as_possible,
      args.out_dir, args.checkpoints, true,       navd::sim_dive_identity(sim)};
  if (args.checkpoints) {
    spdlog::info("navd: checkpoints in {} (input '{}')", config.checkpoint.path,
                 replay.checkpoint_identity);
  }
  return navd::run_replay_mode(config, replay, signals, notifier);
}

int run(const Args& args, const sigset_t& signals) {
  daemon::NavdConfig config = daemon::load_config_file(args.config_path);
  if (!args.lcm_url.empty()) config.lcm.url = args.lcm_url;
  const daemon::SdNotifier notifier;
  if (!args.replay.empty()) {
    const navd::ReplayModeArgs replay{
        args.replay,  args.config_path, args.speed, args.as_fast_as_possible,
        args.out_dir, args.checkpoints, false,      ""};
    return navd::run_replay_mode(config, replay, signals, notifier);
  }
  if (navd::has_device_sensors(config)) {
    const navd::LiveModeArgs live{args.config_path, args.duration_s, args.checkpoints};
    return navd::run_live_mode(config, live, signals, notifier);
  }
  if (config.sim) return run_default_mode(config, args, signals, notifier);
  throw daemon::ConfigError(args.config_path, "sim",
                            "no --replay, no sensor with a hardware transport and no `sim` "
                            "section: nothing to run");
}

}  // namespace

int main(int argc, char** argv) {
  // First of all, so that a SIGTERM during start-up (config, resume, simulation) is held
  // pending for the mode's wait instead of killing the process with its default action.
  const sigset_t signals = block_stop_signals();
  spdlog::set_default_logger(spdlog::stderr_color_mt("navd"));
  CLI::App app{"navd: navigation daemon (view-based SLAM information filter, ESDF)"};
  Args args;
  add_options(app, args);
  CLI11_PARSE(app, argc, argv);
  try {
    return run(args, signals);
  } catch (const nav::daemon::ConfigError& e) {
    spdlog::error("navd: configuration: {}", e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    spdlog::error("navd: {}", e.what());
    return 2;
  } catch (const std::runtime_error& e) {
    spdlog::error("navd: {}", e.what());
    return 1;
  }
}
