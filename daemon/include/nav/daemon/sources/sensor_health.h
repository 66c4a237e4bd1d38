#pragma once
// Per-sensor health of the device sources (device_source.h): counters written by each sensor's
// driver thread with relaxed atomics, read by the publisher thread as navlcm::sensor_health_t
// (lcmtypes/sensor_health_t.lcm) for navd's health_t message.
//
// Threads: SensorHealth entries are created at start-up (the board's size never changes); one
// driver thread writes an entry, any thread reads it; snapshot() belongs to one reader (the
// publisher: it keeps the previous message counts to compute rates).

#include <atomic>
#include <cstdint>
#include <memory>
#include <navlcm/sensor_health_t.hpp>
#include <string>
#include <vector>

#include "nav/daemon/config/config.h"
#include "nav/daemon/sources/sensor_decoder.h"

namespace nav::daemon {

struct SensorHealth {
  explicit SensorHealth(std::string sensor_name) : name(std::move(sensor_name)) {}
  const std::string name;
  std::atomic<bool> active{false};     ///< a device thread runs for this sensor
  std::atomic<bool> connected{false};  ///< the device is open and delivering
  std::atomic<std::uint64_t> bytes{0}, messages{0}, measurements{0}, decode_errors{0},
      dropped_bytes{0}, queue_drops{0}, reconnects{0}, disconnects{0}, open_failures{0};
  /// Host CLOCK_MONOTONIC (µs) of the latest decoded record; -1 before the first.
  std::atomic<std::int64_t> last_message_monotonic_us{-1};

  /// Copies a decoder's counters (bytes, messages, decode errors, dropped bytes, measurements).
  void store(const SensorDecoderCounters& c);
};

class SensorHealthBoard {
 public:
  /// One entry per configured sensor, in config order.
  explicit SensorHealthBoard(const NavdConfig& config);
  std::size_t size() const { return sensors_.size(); }
  SensorHealth& at(std::size_t sensor_index) { return *sensors_.at(sensor_index); }
  const SensorHealth& at(std::size_t sensor_index) const { return *sensors_.at(sensor_index); }

  /// The active sensors' health at host monotonic time `now_us`; rate_hz = records since the
  /// previous snapshot / elapsed time (0 on the first call).
  std::vector<navlcm::sensor_health_t> snapshot(std::int64_t now_us);

 private:
  std::vector<std::unique_ptr<SensorHealth>> sensors_;
  std::vector<std::uint64_t> previous_messages_;
  std::int64_t previous_us_ = -1;
};

}  // namespace nav::daemon
