// The dive-log source (nav/daemon/sources/dive_log_source.h): a recorded dive through the same
// sensor decoders as the vehicle's driver threads, into the MeasurementQueue.
#include "nav/daemon/sources/dive_log_source.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <ctime>
#include <memory>
#include <stdexcept>
#include <thread>

#include "nav/daemon/log/dive_log.h"
#include "nav/daemon/system/host_clock.h"

namespace nav::daemon {
namespace {

bool same_ignoring_case(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::toupper(static_cast<unsigned char>(x)) ==
                  std::toupper(static_cast<unsigned char>(y));
         });
}

/// Sets `done` when the source returns or throws, so the consumer never waits forever.
struct DoneGuard {
  std::atomic<bool>& done;
  ~DoneGuard() { done.store(true); }
};

class Pacer {
 public:
  Pacer(const DiveLogSourceOptions& options, const MeasurementQueue& queue,
        const std::atomic<bool>& stop)
      : options_(options), queue_(queue), stop_(stop) {
    if (!options.as_fast_as_possible && !(options.speed > 0.0)) {
      throw std::invalid_argument("dive log source: speed must be > 0, got " +
                                  std::to_string(options.speed));
    }
  }
  /// Waits until log time `t_us` is due (paced) or for queue room (as fast as possible).
  void wait(std::int64_t t_us) {
    using std::chrono::microseconds;
    if (options_.as_fast_as_possible) {
      while (!stop_.load() && queue_.size() > queue_.capacity() / 2) {
        std::this_thread::sleep_for(microseconds(200));
      }
      return;
    }
    if (!started_) {
      started_ = true;
      log_start_us_ = t_us;
      wall_start_us_ = monotonic_us();
    }
    const double log_elapsed_us = static_cast<double>(std::max(t_us - log_start_us_, latest_));
    latest_ = static_cast<std::int64_t>(log_elapsed_us);
    const std::int64_t due_us = wall_start_us_ + std::llround(log_elapsed_us / options_.speed);
    for (std::int64_t now = monotonic_us(); now < due_us && !stop_.load(); now = monotonic_us()) {
      std::this_thread::sleep_for(microseconds(std::min<std::int64_t>(due_us - now, 10'000)));
    }
  }

 private:
  DiveLogSourceOptions options_;
  const MeasurementQueue& queue_;
  const std::atomic<bool>& stop_;
  bool started_ = false;
  std::int64_t log_start_us_ = 0, wall_start_us_ = 0, latest_ = 0;
};

class DiveLogPlayer {
 public:
  DiveLogPlayer(const NavdConfig& config, const DiveLogSourceOptions& options,
                MeasurementQueue& queue, const std::atomic<bool>& stop)
      : config_(config),
        producer_(queue.make_producer("dive_log")),
        pacer_(options, queue, stop),
        decoders_(config.sensors.size()) {
    for (std::size_t i = 0; i < config.sensors.size(); ++i) {
      const SensorConfig& s = config.sensors[i];
      if (has_sensor_decoder(s.type)) {
        decoders_[i] = make_sensor_decoder(s, static_cast<std::uint16_t>(i));
      } else if (camera_index_ < 0) {
        camera_index_ = static_cast<int>(i);
      }
    }
    counters_.sensors.resize(config.sensors.size());
  }

  void play(const DiveLogEvent& event) {
    if (const auto* raw = std::get_if<navlcm::raw_bytes_t>(&event)) {
      play_raw(*raw);
    } else if (const auto* image = std::get_if<navlcm::image_metadata_t>(&event)) {
      play_image(*image);
    } else {
      ++counters_.registrations;
    }
  }

  DiveLogSourceCounters finish(std::int64_t events) {
    counters_.events = static_cast<std::uint64_t>(events);
    for (std::size_t i = 0; i < decoders_.size(); ++i) {
      if (!decoders_[i]) continue;
      counters_.sensors[i] = decoders_[i]->counters();
      counters_.decode_errors += counters_.sensors[i].decode_errors;
    }
    return counters_;
  }

 private:
  int find_sensor(const navlcm::raw_bytes_t& raw) const {
    for (std::size_t i = 0; i < config_.sensors.size(); ++i)
      if (decoders_[i] && config_.sensors[i].name == raw.device) return static_cast<int>(i);
    for (std::size_t i = 0; i < config_.sensors.size(); ++i)
      if (decoders_[i] && same_ignoring_case(config_.sensors[i].name, raw.device))
        return static_cast<int>(i);
    return -1;
  }

  void note_time(std::int64_t monotonic_us) {
    if (!seen_time_) counters_.first_monotonic_us = monotonic_us;
    seen_time_ = true;
    counters_.last_monotonic_us = std::max(counters_.last_monotonic_us, monotonic_us);
  }

  void push_all() {
    for (const Measurement& m : scratch_) {
      if (producer_.push(m)) {
        ++counters_.measurements;
      } else {
        ++counters_.queue_drops;
      }
    }
    scratch_.clear();
  }

  void play_raw(const navlcm::raw_bytes_t& raw) {
    realtime_minus_monotonic_us_ = raw.utime - raw.host_monotonic_us;
    have_offset_ = true;
    note_time(raw.host_monotonic_us);
    const int index = find_sensor(raw);
    if (index < 0) {
      ++counters_.unknown_devices;
      return;
    }
    ++counters_.raw_messages;
    pacer_.wait(raw.host_monotonic_us);
    decoders_[static_cast<std::size_t>(index)]->feed(raw.data, raw.utime, raw.host_monotonic_us,
                                                     scratch_);
    push_all();
  }

  void play_image(const navlcm::image_metadata_t& image) {
    const std::int64_t host_monotonic_us =
        have_offset_ ? image.utime - realtime_minus_monotonic_us_ : image.time_of_validity_us;
    note_time(host_monotonic_us);
    if (camera_index_ < 0) {
      ++counters_.images_without_camera;
      return;
    }
    pacer_.wait(host_monotonic_us);
    ImageEvent e;
    e.time.validity_us = image.time_of_validity_us;
    e.time.host_monotonic_us = host_monotonic_us;
    e.time.host_realtime_us = image.utime;
    e.time.sensor_index = static_cast<std::uint16_t>(camera_index_);
    e.frame_id = static_cast<std::uint64_t>(image.frame_id);
    scratch_.emplace_back(e);
    ++counters_.images;
    push_all();
  }

  const NavdConfig& config_;
  MeasurementQueue::Producer producer_;
  Pacer pacer_;
  std::vector<std::unique_ptr<SensorDecoder>> decoders_;  ///< by sensor index, null for cameras
  int camera_index_ = -1;
  std::vector<Measurement> scratch_;
  DiveLogSourceCounters counters_;
  std::int64_t realtime_minus_monotonic_us_ = 0;
  bool have_offset_ = false;
  bool seen_time_ = false;
};

}  // namespace

RegistrationTable load_registrations(const std::string& log_path) {
  RegistrationTable table;
  DiveLogReader reader(log_path);
  while (const std::optional<DiveLogEvent> event = reader.next()) {
    const auto* r = std::get_if<navlcm::registration_t>(&*event);
    if (r == nullptr) continue;
    try {
      table.insert(registration_from_message(*r));
    } catch (const std::invalid_argument& e) {
      throw DiveLogError(log_path + ": event " + std::to_string(reader.events_read()) + ": " +
                         e.what());
    }
  }
  return table;
}

DiveLogSourceCounters run_dive_log_source(const std::string& log_path, const NavdConfig& config,
                                          const DiveLogSourceOptions& options,
                                          MeasurementQueue& queue, const std::atomic<bool>& stop,
                                          std::atomic<bool>& done) {
  DoneGuard guard{done};
  DiveLogReader reader(log_path);
  DiveLogPlayer player(config, options, queue, stop);
  while (!stop.load()) {
    const std::optional<DiveLogEvent> event = reader.next();
    if (!event) break;
    player.play(*event);
  }
  return player.finish(reader.events_read());
}

}  // namespace nav::daemon
