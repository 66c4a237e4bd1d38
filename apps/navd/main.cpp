// navd: the navigation daemon on the vehicle. One filter path in every mode: a source ->
// MeasurementQueue -> time ordering -> NavFilter (view-based SLAM, ESDF) -> LCM publishers; the
// modes live in the service library (nav/daemon/service/).
//   navd --config VEHICLE.yaml [--checkpoints] [--duration-s S]
//        a sensor has a hardware transport: the device threads are the source (live_mode.h)
//   navd --config C --replay DIVE.lcmlog [--speed X | --as-fast-as-possible] [--out DIR]
//        [--checkpoints]: the dive log is the source (replay_mode.h)
//   --clock-offset-file F (debugging / HIL): CLOCK_REALTIME is read as the kernel's plus the
//        seconds in F, re-read every 100 ms (nav/daemon/system/wall_clock.h)
// A config whose sensors are all simulated (config/sim.yaml) is refused with the command that
// runs it: `navtool survey` simulates that dive, replays it through the same replay mode and
// writes the report; navd itself links neither the simulator nor the report.
// SIGTERM/SIGINT stop every mode within a second (STOPPING=1), exit 0.
// Exit status: 0 done or stopped, 1 the filter failed, 2 bad arguments or configuration.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <optional>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/daemon/service/live_mode.h"
#include "nav/daemon/service/replay_mode.h"
#include "nav/daemon/system/realtime.h"
#include "nav/daemon/system/sd_notify.h"
#include "nav/daemon/system/stop_signals.h"
#include "nav/daemon/system/wall_clock.h"

namespace {

using namespace nav;

struct Args {
  std::string config_path;
  double speed = 1.0;
  bool as_fast_as_possible = false;
  std::string lcm_url;
  double duration_s = 0.0;        ///< live mode: 0 until a signal
  std::string replay;             ///< a dive log to replay
  std::string out_dir;            ///< replay output directory (replay mode)
  bool checkpoints = false;       ///< every mode: resume from / write checkpoints
  std::string clock_offset_file;  ///< debugging / HIL: the realtime offset seam
};

void add_options(CLI::App& app, Args& args) {
  app.add_option("--config", args.config_path, "navd YAML configuration")->required();
  auto* speed = app.add_option("--speed", args.speed, "replay speed, x real time")
                    ->check(CLI::PositiveNumber);
  app.add_flag("--as-fast-as-possible", args.as_fast_as_possible, "replay without pacing")
      ->excludes(speed);
  app.add_option("--lcm-url", args.lcm_url, "LCM URL (overrides lcm.url)");
  app.add_option("--replay", args.replay, "replay this dive log (hil-tests/README.md)")
      ->check(CLI::ExistingFile);
  app.add_option("--out", args.out_dir, "replay mode: write the replay output directory");
  app.add_flag("--checkpoints", args.checkpoints,
               "every mode: resume from the newest valid checkpoint of this input (the replayed "
               "log or 'live') in checkpoint.path and write checkpoints there (period_s, at "
               "the end)");
  app.add_option("--duration-s", args.duration_s,
                 "live mode: stop after this many seconds (0: no limit)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--clock-offset-file", args.clock_offset_file,
                 "debugging / HIL: read CLOCK_REALTIME as the kernel's plus the seconds in this "
                 "file (re-read every 100 ms; missing or empty: 0) to step navd's wall clock "
                 "alone");
}

int run(const Args& args, const sigset_t& signals) {
  daemon::NavdConfig config = daemon::load_config_file(args.config_path);
  if (!args.lcm_url.empty()) config.lcm.url = args.lcm_url;
  const daemon::SdNotifier notifier;
  std::optional<daemon::ClockOffsetFile> clock_offset;
  if (!args.clock_offset_file.empty()) {
    spdlog::warn("navd: CLOCK_REALTIME offset by the seconds in {} (--clock-offset-file)",
                 args.clock_offset_file);
    clock_offset.emplace(args.clock_offset_file);
  }
  if (!args.replay.empty()) {
    const daemon::service::ReplayModeArgs replay{.log_path = args.replay,
                                                 .config_path = args.config_path,
                                                 .speed = args.speed,
                                                 .as_fast_as_possible = args.as_fast_as_possible,
                                                 .out_dir = args.out_dir,
                                                 .checkpoints = args.checkpoints,
                                                 .checkpoint_identity = ""};
    return daemon::service::run_replay_mode(config, replay, signals, notifier);
  }
  if (daemon::service::has_device_sensors(config)) {
    const daemon::service::LiveModeArgs live{args.config_path, args.duration_s, args.checkpoints};
    return daemon::service::run_live_mode(config, live, signals, notifier);
  }
  if (config.sim) {
    const std::string survey = "`navtool survey --config " + args.config_path + "`";
    throw daemon::ConfigError(
        args.config_path, "sensors",
        "every sensor's transport is `sim`: navd runs on the vehicle's devices or replays a dive "
        "log (--replay DIVE/dive.lcmlog); the simulated survey of the `sim` section is run by " +
            survey);
  }
  throw daemon::ConfigError(args.config_path, "sim",
                            "no --replay, no sensor with a hardware transport and no `sim` "
                            "section: nothing to run");
}

}  // namespace

int main(int argc, char** argv) {
  // First of all, so that a SIGTERM during start-up (config, resume) is held
  // pending for the mode's wait instead of killing the process with its default action.
  const sigset_t signals = daemon::block_stop_signals();
  daemon::keep_freed_memory();
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
