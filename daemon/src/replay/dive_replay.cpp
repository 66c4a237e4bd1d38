// run_replay: dive-log source thread -> queue -> time ordering -> NavFilter (+ dead reckoning).
#include "nav/daemon/replay/dive_replay.h"

#include <spdlog/spdlog.h>

#include <atomic>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <thread>

#include "nav/daemon/checkpoint/nav_filter_checkpointer.h"
#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/replay/filter_worker.h"
#include "nav/daemon/checkpoint/resume_point.h"

namespace nav::daemon {
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Checkpointing of the SLAM filter (ReplayOptions::checkpoints).
struct Checkpointing {
  std::optional<ResumeSkipper> skipper;
  std::unique_ptr<NavFilterCheckpointer> checkpointer;
};

/// Records the SLAM filter's published solution once per period of data time.
struct PublishedRecorder {
  std::int64_t period_us = 100'000;
  std::int64_t next_us = std::numeric_limits<std::int64_t>::min();

  void after(const NavFilter& slam, std::vector<PublishedSolution>& out) {
    if (!slam.initialised() || slam.time_us() < next_us) return;
    PublishedSolution p;
    p.t_us = slam.time_us();
    p.pose = slam.robot_mean().head<6>();
    p.covariance = slam.robot_covariance().topLeftCorner<6, 6>();
    out.push_back(p);
    // On the grid first + k·period (a rate of exactly 1/period while measurements come faster).
    if (next_us == std::numeric_limits<std::int64_t>::min()) next_us = p.t_us;
    while (next_us <= p.t_us) next_us += period_us;
  }
};

/// Feeds one time-ordered measurement to both filters (the SLAM filter only if its checkpoint
/// does not hold it yet; dead reckoning through its worker thread); false on a failure (run.error
/// set for the SLAM filter; dead reckoning's message comes from FilterWorker::finish()).
bool filter_one(ReplayRun& run, const Measurement& m,
                const std::function<void(const NavFilter&)>& after, Checkpointing& ckpt,
                PublishedRecorder& published, FilterWorker* dead_reckoning,
                vision::VisionLink* vision) {
  const bool held = ckpt.skipper && ckpt.skipper->skip(m);
  if (!held) {
    if (vision) vision->before_measurement(time_of(m).host_realtime_us, *run.registrations);
    if (core::Status s = run.slam->process(m); !s.ok()) {
      run.error = "SLAM filter at t = " + std::to_string(validity_us(m)) + " us: " + s.to_string();
      return false;
    }
    if (ckpt.checkpointer) ckpt.checkpointer->after_measurement(*run.slam, m);
    if (vision) vision->after_measurement(*run.slam);
    if (after) after(*run.slam);
    published.after(*run.slam, run.published);
  }
  if (dead_reckoning) {
    dead_reckoning->push(m);
    if (dead_reckoning->failed()) return false;
  }
  return true;
}

/// vision.enabled: navd's own vision stage on the dive's frames (vision/vision_link.h).
std::unique_ptr<vision::VisionLink> make_vision(const std::string& log_path,
                                                const NavdConfig& config) {
  if (!config.vision.enabled) return nullptr;
  if (!(config.filter.registration_wait_s > config.vision.answer_delay_s)) {
    throw std::invalid_argument(
        "vision: filter.registration_wait_s (" + std::to_string(config.filter.registration_wait_s) +
        " s) must exceed vision.answer_delay_s (" + std::to_string(config.vision.answer_delay_s) +
        " s), else every proposed pair expires before its answer");
  }
  const std::string dir =
      config.vision.image_dir.empty()
          ? (std::filesystem::path(log_path).parent_path() / "images").string()
          : config.vision.image_dir;
  return std::make_unique<vision::VisionLink>(config, dir, vision::VisionLink::Mode::kReplay);
}

/// ReplayOptions::time_of_use_every_images: the filter's observer before each link proposal.
void check_time_of_use_at_images(const ReplayOptions& options, ReplayRun& run) {
  if (options.time_of_use_every_images <= 0) return;
  run.slam->set_before_proposal([&options, &run](const NavFilter& slam) {
    const std::size_t image = slam.images().size() - 1;
    if (image % static_cast<std::size_t>(options.time_of_use_every_images) != 0) return;
    if (!run.error.empty()) return;
    const auto start = std::chrono::steady_clock::now();
    try {
      core::check_time_of_use(slam.esdf(), slam.bounds(), slam.recovery(),
                              {.markov_blanket = options.time_of_use_markov_blanket},
                              run.time_of_use);
      run.time_of_use_frames.push_back(slam.images().back().frame_id);
    } catch (const std::exception& e) {
      run.error = "time-of-use check at frame " + std::to_string(slam.images().back().frame_id) +
                  ": " + e.what();
    }
    run.time_of_use_s += seconds_since(start);
  });
}

}  // namespace

ReplayRun run_replay(const std::string& log_path, const NavdConfig& config,
                     const ReplayOptions& options) {
  ReplayRun run;
  run.log_path = log_path;
  std::unique_ptr<vision::VisionLink> vision = make_vision(log_path, config);
  run.registrations = vision ? std::make_unique<RegistrationTable>()
                             : std::make_unique<RegistrationTable>(load_registrations(log_path));
  const NavFilterOptions filter_options = filter_options_from_config(config);
  run.slam = std::make_unique<NavFilter>(filter_options, run.registrations.get());
  if (options.dead_reckoning) {
    run.dead_reckoning = std::make_unique<core::DeadReckoningFilter>(filter_options);
  }
  PublishedRecorder published;
  published.period_us = std::max<std::int64_t>(
      1, static_cast<std::int64_t>(std::llround(1e6 / config.lcm.nav_solution.rate_hz)));
  Checkpointing ckpt;
  if (options.checkpoints) {
    const std::string& identity =
        options.checkpoint_identity.empty() ? log_path : options.checkpoint_identity;
    ResumedNavFilter resumed = resume_nav_filter(
        config.checkpoint.path,
        [&] { return std::make_unique<NavFilter>(filter_options, run.registrations.get()); },
        identity);
    for (const SkippedCheckpoint& k : resumed.skipped) {
      spdlog::warn("navd: checkpoint {} skipped: {}", k.path.string(), k.reason);
    }
    if (resumed.filter) {
      run.slam = std::move(resumed.filter);
      run.resumed_from = resumed.path.string();
      run.resumed_measurements = resumed.point.applied;
      ckpt.skipper.emplace(resumed.point);
      spdlog::info("navd: resumed from {} ({} measurements applied)", run.resumed_from,
                   resumed.point.applied);
    }
    ckpt.checkpointer =
        std::make_unique<NavFilterCheckpointer>(config.checkpoint, resumed.point, identity);
  }
  check_time_of_use_at_images(options, run);
  TimeOrderingOptions ordering_options;
  ordering_options.latency_window_us =
      static_cast<std::int64_t>(config.filter.latency_window_ms * 1e3);
  TimeOrderingBuffer ordering(ordering_options);
  std::unique_ptr<MeasurementQueue> own_queue;
  if (!options.queue) own_queue = std::make_unique<MeasurementQueue>(options.queue_capacity);
  MeasurementQueue& queue = options.queue ? *options.queue : *own_queue;
  DiveLogSourceOptions source_options;
  source_options.speed = options.speed;
  source_options.as_fast_as_possible = options.as_fast_as_possible;

  std::atomic<bool> stop{false}, done{false};
  std::string source_error;
  const auto start = std::chrono::steady_clock::now();
  // Dead reckoning runs on its own thread (the second core), fed the same ordered measurements.
  std::unique_ptr<FilterWorker> dr_worker;
  if (run.dead_reckoning) {
    dr_worker = std::make_unique<FilterWorker>(
        [dr = run.dead_reckoning.get()](const Measurement& m) { return dr->process(m); },
        "dead-reckoning filter");
  }
  std::thread source([&] {
    try {
      run.source = run_dive_log_source(log_path, config, source_options, queue, stop, done);
    } catch (const std::exception& e) {
      source_error = e.what();
      done.store(true);
    }
  });
  std::vector<Measurement> batch;
  batch.reserve(256);
  bool ok = true;
  auto stopped = [&] { return options.stop && options.stop->load(); };
  while (ok && !stopped()) {
    const bool source_done = done.load();
    batch.clear();
    queue.pop_bulk(batch, 256);
    for (const Measurement& m : batch) ordering.insert(m);
    while (ok) {
      std::optional<Measurement> m = ordering.pop_ready();
      if (!m) break;
      ok = filter_one(run, *m, options.after_measurement, ckpt, published, dr_worker.get(),
                      vision.get());
    }
    if (source_done && batch.empty() && queue.size() == 0) break;
    if (batch.empty()) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  while (ok && !stopped()) {
    std::optional<Measurement> m = ordering.pop_any();
    if (!m) break;
    ok = filter_one(run, *m, options.after_measurement, ckpt, published, dr_worker.get(),
                    vision.get());
  }
  stop.store(true);
  source.join();
  // The shutdown checkpoint: the filter as it stands (before finish(), which only closes a
  // pending image for the outputs).
  if (ok && ckpt.checkpointer) ckpt.checkpointer->shutdown(*run.slam);
  if (ok) {
    if (core::Status s = run.slam->finish(); !s.ok()) run.error = "SLAM finish: " + s.to_string();
  }
  if (dr_worker) {
    const std::string dr_error = dr_worker->finish();
    if (run.error.empty() && !dr_error.empty()) run.error = dr_error;
  }
  run.wall_s = seconds_since(start) - run.time_of_use_s;
  run.slam->set_before_proposal({});  // it refers to this frame's `run` and `options`
  if (vision) {
    run.vision = vision->stats();
    run.vision_answers = vision->applied();
  }
  run.ordering = ordering.stats();
  run.log_span_s =
      1e-6 * static_cast<double>(run.source.last_monotonic_us - run.source.first_monotonic_us);
  if (!source_error.empty()) run.error = "dive log " + log_path + ": " + source_error;
  if (!run.error.empty()) spdlog::error("replay: {}", run.error);
  return run;
}

}  // namespace nav::daemon
