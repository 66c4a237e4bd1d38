#pragma once
// Device sources: the driver thread of one serial or CAN sensor on the vehicle
// (docs/architecture.md "Data flow"). Each loop reads its transport, publishes every read as
// navlcm::raw_bytes_t on RAW_<NAME> (so `lcm-logger` records a dive that dive_log_source.h replays
// identically), decodes it with the sensor's SensorDecoder and pushes the measurements into the
// MeasurementQueue (a full queue drops and counts: a live driver never waits for the filter).
// Health (bytes, records, decode errors, queue drops, reconnects, last record time) goes to the
// sensor's SensorHealth entry.
//
// Reconnection: a serial ByteStream (drivers::SerialPort) reopens its device itself with
// exponential backoff and reports kDisconnected meanwhile; the loop counts a disconnect when a
// delivering device stops and a reconnect when it delivers again. A CAN bus is reopened by the
// loop through its opener, with backoff from DeviceLoopOptions. Errors returned early are
// followed by a pause of one read timeout, so a missing device never spins a core.
// CAN raw bytes: one candump log line per frame (sensor_decoder.h, can_frame_log_line).
//
// Threads: each loop runs on its own thread until `stop`; LcmRawPublisher::publish_* may be
// called from every driver thread (serialised by a mutex: lcm::LCM::publish is not documented
// as thread-safe for every provider).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <navlcm/image_metadata_t.hpp>
#include <span>
#include <string>

#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/sources/sensor_decoder.h"
#include "nav/daemon/sources/sensor_health.h"
#include "nav/drivers/transports/byte_stream.h"
#include "nav/drivers/transports/can_bus.h"

namespace lcm {
class LCM;
}

namespace nav::daemon {

/// Thread-safe publishing of RAW_<NAME> and NAV_IMAGE on an lcm::LCM owned by the caller.
class LcmRawPublisher {
 public:
  /// `lcm` may be null: nothing is published (counted as not published).
  explicit LcmRawPublisher(lcm::LCM* lcm) : lcm_(lcm) {}
  bool publish_raw(const std::string& sensor_name, std::int64_t host_realtime_us,
                   std::int64_t host_monotonic_us, std::span<const std::uint8_t> bytes);
  bool publish_image(const navlcm::image_metadata_t& image);
  std::uint64_t published() const { return published_.load(); }
  std::uint64_t failures() const { return failures_.load(); }

 private:
  lcm::LCM* lcm_;
  std::mutex mutex_;
  std::atomic<std::uint64_t> published_{0}, failures_{0};
};

struct DeviceLoopOptions {
  std::chrono::milliseconds read_timeout{100};  ///< longest wait per read (stop latency)
  std::size_t read_buffer_bytes = 4096;
  std::chrono::milliseconds reconnect_initial{100};  ///< CAN reopen backoff, doubles ...
  std::chrono::milliseconds reconnect_max{5000};     ///< ... up to this
};

/// What every device loop works with; all references outlive the loop.
struct DeviceLoopContext {
  SensorDecoder& decoder;
  MeasurementQueue::Producer& producer;
  LcmRawPublisher* raw = nullptr;  ///< null: raw bytes are not published
  SensorHealth& health;
  const std::atomic<bool>& stop;
  DeviceLoopOptions options;
};

/// Serial-type sensors: reads `stream` until stop.
void run_byte_device(drivers::ByteStream& stream, DeviceLoopContext& context);

/// Opens a CAN bus (e.g. SocketCanBus::open_interface); null with `status` set on failure.
using CanBusOpener = std::function<std::unique_ptr<drivers::CanBus>(drivers::IoStatus& status)>;

/// CAN sensors: opens the bus with `open` (again after a failure, with backoff), receives
/// frames until stop. `interface` names the bus in the raw candump lines.
void run_can_device(const CanBusOpener& open, const std::string& interface,
                    DeviceLoopContext& context);

}  // namespace nav::daemon
