#include "nav/daemon/service/live_mode.h"

#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "nav/core/navigation/nav_filter.h"
#include "nav/daemon/checkpoint/nav_filter_checkpointer.h"
#include "nav/daemon/checkpoint/resume_point.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/queue/time_ordering.h"
#include "nav/daemon/service/lcm_url.h"
#include "nav/daemon/service/link_publisher.h"
#include "nav/daemon/service/navd_devices.h"
#include "nav/daemon/service/publisher.h"
#include "nav/daemon/service/registration_listener.h"
#include "nav/daemon/service/solution_board.h"
#include "nav/daemon/service/vision_answers.h"
#include "nav/daemon/sources/device_sources.h"
#include "nav/daemon/system/realtime.h"

namespace nav::daemon::service {
namespace {

constexpr std::size_t kQueueCapacity = 4096;
constexpr std::size_t kRegistrationCapacity = 1024;  ///< registrations queued for the filter
constexpr const char* kLiveIdentity = "live";
/// How long a stop waits for the device threads after the filter thread has saved its final
/// checkpoint; threads still inside a device call then are abandoned and the process ends
/// (the stop contract: within 1 s even when a GigE camera hung or vanished).
constexpr std::chrono::milliseconds kDeviceStopGrace{300};
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// The SLAM filter of the live mode, resumed from a checkpoint when asked.
struct LiveFilter {
  /// The vision stage's answers (registration_listener.h); declared first: outlives `slam`.
  std::unique_ptr<daemon::RegistrationInbox> inbox;
  std::unique_ptr<LinkProposalPublisher> proposals;
  /// vision.enabled: navd's own vision stage answering the proposals (vision_answers.h);
  /// the link is declared after its publisher, so its threads stop first.
  std::unique_ptr<VisionAnswerPublisher> vision_answers;
  std::unique_ptr<daemon::vision::VisionLink> vision;
  std::unique_ptr<daemon::NavFilter> slam;
  std::optional<daemon::ResumeSkipper> skipper;
  std::unique_ptr<daemon::NavFilterCheckpointer> checkpointer;
};

LiveFilter make_live_filter(const daemon::NavdConfig& config, bool checkpoints) {
  const daemon::NavFilterOptions options = daemon::filter_options_from_config(config);
  LiveFilter live;
  // A fresh run id per process (also after a resume): answers to an earlier run's proposals,
  // e.g. a replayed log, are rejected (proposal_ledger.h).
  const std::int64_t run_id = daemon::draw_run_id();
  spdlog::info("navd: run id {:016x}", static_cast<std::uint64_t>(run_id));
  live.inbox = std::make_unique<daemon::RegistrationInbox>(kRegistrationCapacity, run_id);
  live.proposals = std::make_unique<LinkProposalPublisher>(config, live.inbox->ledger());
  if (config.vision.enabled) {
    live.vision_answers = std::make_unique<VisionAnswerPublisher>(config.lcm, run_id);
    live.vision = make_live_vision(config, *live.vision_answers);
  }
  const daemon::RegistrationTable* table = &live.inbox->table();
  auto make = [&] { return std::make_unique<daemon::NavFilter>(options, table); };
  live.slam = make();
  if (!checkpoints) return live;
  daemon::ResumedNavFilter resumed =
      daemon::resume_nav_filter(config.checkpoint.path, make, kLiveIdentity);
  for (const daemon::SkippedCheckpoint& k : resumed.skipped) {
    spdlog::warn("navd: checkpoint {} skipped: {}", k.path.string(), k.reason);
  }
  if (resumed.filter) {
    live.slam = std::move(resumed.filter);
    live.skipper.emplace(resumed.point);
    spdlog::info("navd: resumed from {} ({} measurements applied)", resumed.path.string(),
                 resumed.point.applied);
  }
  live.checkpointer = std::make_unique<daemon::NavFilterCheckpointer>(config.checkpoint,
                                                                      resumed.point, kLiveIdentity);
  return live;
}

/// Feeds one time-ordered measurement to the filter; the error (what, when) or "".
std::string filter_one(LiveFilter& live, const daemon::Measurement& m, LinkPublisher& links) {
  if (live.skipper && live.skipper->skip(m)) return {};
  if (core::Status s = live.slam->process(m); !s.ok()) {
    return "SLAM filter at t = " + std::to_string(daemon::validity_us(m)) + " us: " + s.to_string();
  }
  if (live.checkpointer) live.checkpointer->after_measurement(*live.slam, m);
  links.on_measurement(*live.slam);
  live.proposals->on_measurement(*live.slam);
  if (live.vision) live.vision->after_measurement(*live.slam);
  return {};
}

/// The filter thread: queue -> time ordering -> filter until `stop`; the error or "".
/// `dropped_late`: measurements the ordering refused as older than what the filter has applied.
std::string filter_loop(const daemon::NavdConfig& config, daemon::MeasurementQueue& queue,
                        LiveFilter& live, LinkPublisher& links, const std::atomic<bool>& stop,
                        std::uint64_t& dropped_late) {
  daemon::TimeOrderingOptions ordering_options;
  ordering_options.latency_window_us =
      static_cast<std::int64_t>(config.filter.latency_window_ms * 1e3);
  daemon::TimeOrderingBuffer ordering(ordering_options);
  std::vector<daemon::Measurement> batch;
  batch.reserve(256);
  while (!stop.load()) {
    batch.clear();
    queue.pop_bulk(batch, 256);
    for (const daemon::Measurement& m : batch) {
      const std::optional<std::int64_t> applied_us = ordering.last_released_us();
      if (ordering.insert(m) == daemon::TimeOrderingBuffer::InsertResult::kDroppedLate) {
        const core::MeasurementTime& t = core::time_of(m);
        spdlog::warn(
            "navd: a measurement of sensor {} dropped as late: valid {} ms before the last "
            "one applied, received {} ms after its validity (filter.latency_window_ms {})",
            t.sensor_index, (*applied_us - t.validity_us) / 1000,
            (t.host_monotonic_us - t.validity_us) / 1000, config.filter.latency_window_ms);
      }
    }
    if (live.inbox->has_queued()) {  // registrations before the measurements they may answer
      live.inbox->drain(live.slam->pending_registrations());
    }
    while (std::optional<daemon::Measurement> m = ordering.pop_ready()) {
      if (std::string error = filter_one(live, *m, links); !error.empty()) {
        dropped_late = ordering.stats().dropped_late;
        return error;
      }
    }
    dropped_late = ordering.stats().dropped_late;
    if (batch.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (live.checkpointer) live.checkpointer->shutdown(*live.slam);
  return {};
}

/// Waits for a stop signal (returned), the filter's end or the duration (0), feeding the
/// watchdog meanwhile.
int wait_for_end(const sigset_t& signals, const std::atomic<bool>& filter_done,
                 const daemon::SdNotifier& notifier, double duration_s, Clock::time_point start) {
  const timespec tick{0, 20'000'000};
  const auto period = notifier.watchdog_period();
  auto last_watchdog = Clock::now();
  while (!filter_done.load()) {
    const int sig = sigtimedwait(&signals, nullptr, &tick);
    if (sig > 0) return sig;
    if (period && Clock::now() - last_watchdog >= *period) {
      notifier.watchdog();
      last_watchdog = Clock::now();
    }
    if (duration_s > 0.0 && seconds_since(start) >= duration_s) return 0;
  }
  return 0;
}

/// realtime.lock_memory: locks every page of the process in RAM; whether it did (a refusal is
/// logged and navd goes on).
bool lock_memory(const daemon::RealtimeConfig& realtime) {
  if (!realtime.lock_memory) return false;
  if (std::string why = daemon::lock_all_memory(); !why.empty()) {
    spdlog::warn("navd: memory not locked: {}", why);
    return false;
  }
  spdlog::info("navd: memory locked (mlockall, current and future pages)");
  return true;
}

/// Ends the process with `code` without waiting for the device threads still inside a device
/// call (destroying their objects under them is not an option): logs which, flushes, _Exit.
[[noreturn]] void end_abandoning(const std::vector<std::string>& sensors, int code) {
  std::string names;
  for (const std::string& s : sensors) names += (names.empty() ? "" : ", ") + s;
  spdlog::warn(
      "navd: device thread(s) of {} still in a device call {} ms after stop (device hung or "
      "gone); abandoned, exiting {} (final checkpoint already written)",
      names, kDeviceStopGrace.count(), code);
  spdlog::default_logger()->flush();
  std::fflush(stdout);
  std::fflush(stderr);
  std::_Exit(code);
}

}  // namespace

bool has_device_sensors(const daemon::NavdConfig& config) {
  for (const daemon::SensorConfig& sensor : config.sensors) {
    if (daemon::has_device(sensor)) return true;
  }
  return false;
}

int run_live_mode(const daemon::NavdConfig& config, const LiveModeArgs& args,
                  const sigset_t& stop_signals, const daemon::SdNotifier& notifier) {
  std::optional<daemon::SigningKey> key;  // before anything starts: a bad key file stops navd
  if (!config.lcm.registration_signing.key_file.empty()) {
    key = daemon::load_signing_key(config.lcm.registration_signing.key_file);
  }
  const bool memory_locked = lock_memory(config.realtime);
  LiveFilter live = make_live_filter(config, args.checkpoints);
  if (key && live.vision_answers) live.vision_answers->set_signing_key(*key);
  daemon::MeasurementQueue queue(kQueueCapacity);
  SolutionBoard board;
  Publisher publisher(config.lcm, board, queue);
  if (!publisher.good()) spdlog::error("navd: {}", lcm_open_error(config.lcm.url));
  LinkPublisher links(config.lcm, board);
  NavdDevices devices(config, queue);
  devices.attach(publisher);
  publisher.set_vision(live.vision.get());
  RegistrationListener registrations(config.lcm, *live.inbox, std::move(key));
  publisher.set_health_fields(
      [&](navlcm::health_t& h) { fill_registration_health(*live.inbox, registrations, h); });
  if (config.filter.registration_wait_s <= 0.0) {
    spdlog::warn(
        "navd: filter.registration_wait_s is 0: proposed pairs do not wait for the "
        "vision stage, so live mode accepts no camera link (config/README.md)");
  }

  daemon::RealtimeTally filter_realtime;
  std::atomic<bool> stop{false}, filter_done{false};
  std::uint64_t dropped_late = 0;  ///< the filter thread's; read after it is joined
  std::string failure;
  const auto start = Clock::now();
  std::thread filter_thread([&] {
    daemon::name_this_thread("navd-filter");
    filter_realtime.enter("filter", config.realtime.filter_priority);
    try {
      failure = filter_loop(config, queue, live, links, stop, dropped_late);
    } catch (const std::exception& e) {
      failure = e.what();
    }
    filter_done.store(true);
  });
  std::thread publisher_thread([&] {
    daemon::name_this_thread("navd-publisher");
    publisher.run(stop);
  });
  registrations.start(stop);
  const std::size_t device_threads = devices.start(stop);
  spdlog::info("navd: live on {} device threads ({})", device_threads, args.config_path);
  notifier.ready_with_status("live: " + std::to_string(device_threads) + " devices");
  const int sig = wait_for_end(stop_signals, filter_done, notifier, args.duration_s, start);
  if (sig > 0) spdlog::info("navd: signal {}, stopping", sig);
  notifier.stopping();
  stop.store(true);
  const auto device_deadline = Clock::now() + kDeviceStopGrace;
  filter_thread.join();  // writes the final checkpoint: never abandoned
  publisher_thread.join();
  registrations.join();
  const std::vector<std::string> stuck = devices.join_until(device_deadline);
  const daemon::NavFilterCounters& counters = live.slam->counters();
  std::printf(
      "{\"mode\":\"live\",\"measurements\":%llu,\"images\":%zu,\"links\":%zu,"
      "\"devices\":%zu,\"queue_dropped\":%llu,\"dropped_late\":%llu,\"realtime_threads\":%d,"
      "\"realtime_refused\":%d,\"memory_locked\":%s,\"wall_s\":%.3f%s}\n",
      static_cast<unsigned long long>(counters.measurements), live.slam->images().size(),
      live.slam->links().size(), device_threads,
      static_cast<unsigned long long>(queue.total_dropped()),
      static_cast<unsigned long long>(dropped_late),
      devices.realtime().granted() + filter_realtime.granted(),
      devices.realtime().refused() + filter_realtime.refused(), memory_locked ? "true" : "false",
      seconds_since(start),
      registration_summary_json(*live.inbox, registrations, *live.slam).c_str());
  std::fflush(stdout);
  const int code = failure.empty() ? 0 : 1;
  if (!failure.empty()) spdlog::error("navd: live filter: {}", failure);
  if (!stuck.empty()) end_abandoning(stuck, code);
  return code;
}

}  // namespace nav::daemon::service
