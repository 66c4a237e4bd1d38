#include "nav/daemon/service/replay_mode.h"

#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "nav/daemon/system/host_clock.h"
#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/replay/dive_replay.h"
#include "nav/daemon/replay/replay_summary.h"
#include "nav/daemon/service/lcm_url.h"
#include "nav/daemon/service/link_publisher.h"
#include "nav/daemon/service/publisher.h"
#include "nav/daemon/service/solution_board.h"

namespace nav::daemon::service {
namespace {

constexpr std::size_t kQueueCapacity = 4096;

/// Waits for `done` or a stop signal (returned, else 0).
int wait_for(const sigset_t& signals, const std::atomic<bool>& done) {
  const timespec tick{0, 20'000'000};
  while (!done.load()) {
    const int sig = sigtimedwait(&signals, nullptr, &tick);
    if (sig > 0) return sig;
  }
  return 0;
}

}  // namespace

int run_replay_mode(const daemon::NavdConfig& config, const ReplayModeArgs& args,
                    const sigset_t& stop_signals, const daemon::SdNotifier& notifier) {
  daemon::MeasurementQueue queue(kQueueCapacity);
  SolutionBoard board;
  Publisher publisher(config.lcm, board, queue);
  if (!publisher.good()) spdlog::error("navd: {}", lcm_open_error(config.lcm.url));
  LinkPublisher map_publisher(config.lcm, board);

  std::atomic<bool> stop{false}, filter_done{false};
  std::int64_t last_watchdog_us = 0;
  daemon::ReplayOptions options;
  options.speed = args.speed;
  options.as_fast_as_possible = args.as_fast_as_possible;
  options.queue = &queue;
  options.stop = &stop;
  options.checkpoints = args.checkpoints;
  options.checkpoint_identity = args.checkpoint_identity;
  options.time_of_use_every_images = args.time_of_use_every_images;
  options.time_of_use_markov_blanket = args.time_of_use_markov_blanket;
  options.after_measurement = [&](const daemon::NavFilter& filter) {
    map_publisher.on_measurement(filter);
    const auto period = notifier.watchdog_period();
    const std::int64_t now = daemon::monotonic_us();
    if (period && now - last_watchdog_us >= period->count()) {
      notifier.watchdog();
      last_watchdog_us = now;
    }
  };
  daemon::ReplayRun run;
  std::string failure;
  notifier.ready_with_status("replaying " + args.log_path);
  std::thread filter_thread([&] {
    try {
      run = daemon::run_replay(args.log_path, config, options);
    } catch (const std::exception& e) {
      failure = e.what();
    }
    filter_done.store(true);
  });
  std::thread publisher_thread([&] { publisher.run(stop); });
  const int sig = wait_for(stop_signals, filter_done);
  if (sig > 0) spdlog::info("navd: signal {}, stopping", sig);
  notifier.stopping();
  stop.store(true);
  filter_thread.join();
  publisher_thread.join();
  if (!failure.empty() || !run.slam) {
    spdlog::error("navd: replay of {}: {}", args.log_path, failure);
    return 1;
  }
  const daemon::ReplayAnalysis analysis = daemon::analyse(*run.slam);
  const std::string dive_dir = std::filesystem::path(args.log_path).parent_path().string();
  const std::string summary =
      daemon::replay_summary_json(
          daemon::make_replay_summary(run, analysis, dive_dir, args.config_path), run);
  if (!args.out_dir.empty()) daemon::write_replay_outputs(run, analysis, summary, args.out_dir);
  std::printf("%s\n", summary.c_str());
  std::fflush(stdout);
  return run.error.empty() ? 0 : 1;
}

}  // namespace nav::daemon::service
