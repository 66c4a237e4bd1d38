// navd: the navigation daemon on the built-in simulated survey, or on a recorded dive.
//   navd --config config/sim.yaml [--images N] [--seed S] [--speed X | --as-fast-as-possible]
//        [--lcm-url URL] [--duration-s S]
//   navd --config C --replay DIVE.lcmlog [--speed X | --as-fast-as-possible] [--out DIR]
//        (replay_mode.h: NavFilter on the dive's measurements, published on LCM)
//   navd --config VEHICLE.yaml [--checkpoints] [--duration-s S]: when a sensor has a hardware
//        transport, the device threads feed the NavFilter (live_mode.h)
// Threads: sim source -> MeasurementQueue -> filter (owns the Esdf) -> recovery (PCG), and a
// LCM publisher. SIGTERM/SIGINT stop everything within a second (STOPPING=1), exit 0. At the
// end (survey done, signal or --duration-s) one line of JSON goes to stdout (summary.h).
// Exit status: 0 done or stopped, 1 the filter failed, 2 bad arguments or configuration.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <thread>

#include "nav/core/sim/survey.h"
#include "nav/daemon/config.h"
#include "nav/daemon/measurement_queue.h"
#include "nav/daemon/sd_notify.h"
#include "navd/device_sources.h"
#include "navd/filter_loop.h"
#include "navd/live_mode.h"
#include "navd/mailboxes.h"
#include "navd/publisher.h"
#include "navd/recovery_worker.h"
#include "navd/replay_mode.h"
#include "navd/sim_source.h"
#include "navd/summary.h"

namespace {

using namespace nav;

constexpr std::size_t kQueueCapacity = 1024;

struct Args {
  std::string config_path;
  int images = 200;
  std::uint64_t seed = 1;
  double speed = 1.0;
  bool as_fast_as_possible = false;
  std::string lcm_url;
  double duration_s = 0.0;  ///< 0: until the survey ends
  std::string replay;       ///< a dive log to replay instead of the built-in survey
  std::string out_dir;      ///< replay output directory (with --replay)
  bool checkpoints = false;  ///< --replay or live: resume from / write checkpoints
};

void add_options(CLI::App& app, Args& args) {
  app.add_option("--config", args.config_path, "navd YAML configuration")->required();
  app.add_option("--images", args.images, "images in the simulated survey")
      ->check(CLI::Range(1, 100000));
  app.add_option("--seed", args.seed, "seed of the simulated survey");
  auto* speed = app.add_option("--speed", args.speed, "replay speed, x real time")
                    ->check(CLI::PositiveNumber);
  app.add_flag("--as-fast-as-possible", args.as_fast_as_possible, "replay without pacing")
      ->excludes(speed);
  app.add_option("--lcm-url", args.lcm_url, "LCM URL (overrides lcm.url)");
  app.add_option("--replay", args.replay, "replay this dive log (hil-tests/README.md)")
      ->check(CLI::ExistingFile);
  app.add_option("--out", args.out_dir, "with --replay: write the replay output directory");
  app.add_flag("--checkpoints", args.checkpoints,
               "with --replay or on devices: resume from the newest valid checkpoint of this "
               "input in checkpoint.path and write checkpoints there (period_s, at the end)");
  app.add_option("--duration-s", args.duration_s, "stop after this many seconds (0: no limit)")
      ->check(CLI::NonNegativeNumber);
}

/// Blocks SIGTERM/SIGINT in every thread (threads inherit the mask); main waits for them.
sigset_t block_stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  return set;
}

/// Waits until `done`, a stop signal or the duration; returns the signal number or 0.
int wait_for_end(const sigset_t& signals, const std::atomic<bool>& done, double duration_s,
                 std::int64_t start_us) {
  const timespec tick{0, 20'000'000};
  while (!done.load()) {
    const int sig = sigtimedwait(&signals, nullptr, &tick);
    if (sig > 0) return sig;
    if (duration_s > 0.0 && (navd::monotonic_us() - start_us) * 1e-6 >= duration_s) return 0;
  }
  return 0;
}

int run(const Args& args) {
  daemon::NavdConfig config = daemon::load_config_file(args.config_path);
  if (!args.lcm_url.empty()) config.lcm.url = args.lcm_url;
  if (!args.replay.empty()) {
    const navd::ReplayModeArgs replay{args.replay, args.config_path, args.speed,
                                      args.as_fast_as_possible, args.out_dir,
                                      args.checkpoints};
    return navd::run_replay_mode(config, replay, block_stop_signals(), daemon::SdNotifier());
  }
  if (navd::has_device_sensors(config)) {
    const navd::LiveModeArgs live{args.config_path, args.duration_s, args.checkpoints};
    return navd::run_live_mode(config, live, block_stop_signals(), daemon::SdNotifier());
  }
  core::sim::SurveyOptions survey_options;
  survey_options.num_images = args.images;
  survey_options.seed = args.seed;
  const core::sim::Survey survey = core::sim::simulate_survey(survey_options);

  const sigset_t signals = block_stop_signals();
  const daemon::SdNotifier notifier;
  daemon::MeasurementQueue queue(kQueueCapacity);
  navd::RecoveryInbox inbox;
  navd::RecoveryOutbox outbox;
  navd::SolutionBoard board;
  daemon::TimeOrderingOptions ordering;
  ordering.latency_window_us = static_cast<std::int64_t>(config.filter.latency_window_ms * 1e3);
  navd::Publisher publisher(config.lcm, board, queue);
  if (!publisher.good()) {
    spdlog::error("navd: cannot open LCM at '{}'; not publishing", config.lcm.url);
  }
  navd::NavdDevices devices(config, queue);  // sensors with a hardware transport
  devices.attach(publisher);
  navd::FilterLoop filter(survey, queue, ordering, inbox, outbox, board, notifier);
  navd::RecoveryWorker recovery(survey.x0_mean, survey.P0, config.filter.cg_iterations_per_step,
                                inbox, outbox, board);

  std::atomic<bool> stop{false}, source_done{false}, filter_done{false};
  navd::FilterLoopResult filter_result;
  navd::RecoveryCounters recovery_counters;
  navd::PublisherCounters publisher_counters;
  const navd::SimSourceOptions source_options{args.speed, args.as_fast_as_possible};
  const std::int64_t start_us = navd::monotonic_us();

  std::thread source_thread([&] {
    navd::run_sim_source(survey, navd::find_sim_sensors(config), source_options, queue, stop,
                         source_done);
  });
  std::thread filter_thread([&] {
    filter_result = filter.run(stop, source_done);
    filter_done.store(true);
  });
  std::thread recovery_thread([&] { recovery_counters = recovery.run(stop); });
  std::thread publisher_thread([&] { publisher_counters = publisher.run(stop); });
  if (const std::size_t n = devices.start(stop); n > 0) spdlog::info("navd: {} device threads", n);

  const int sig = wait_for_end(signals, filter_done, args.duration_s, start_us);
  if (sig > 0) spdlog::info("navd: signal {}, stopping", sig);
  notifier.stopping();
  stop.store(true);
  for (std::thread* t : {&source_thread, &filter_thread, &recovery_thread, &publisher_thread}) {
    t->join();
  }
  devices.join();
  const double wall_s = (navd::monotonic_us() - start_us) * 1e-6;
  const navd::SolutionView view = board.read();
  const double sigma_m = std::sqrt(view.robot_covariance.topLeftCorner<3, 3>().trace());
  navd::Summary summary{
      survey, filter_result, recovery_counters, publisher_counters, queue.total_dropped(),
      wall_s, sigma_m};
  std::printf("%s\n", navd::summary_json(summary).c_str());
  std::fflush(stdout);
  return filter_result.error.empty() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("navd"));
  CLI::App app{"navd: navigation daemon (ESDF) on the built-in simulated survey"};
  Args args;
  add_options(app, args);
  CLI11_PARSE(app, argc, argv);
  try {
    return run(args);
  } catch (const nav::daemon::ConfigError& e) {
    spdlog::error("navd: configuration: {}", e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    spdlog::error("navd: {}", e.what());
    return 2;
  }
}
