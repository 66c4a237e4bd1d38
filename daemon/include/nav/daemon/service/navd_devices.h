#pragma once
// navd's glue for the device threads (nav/daemon/sources/device_sources.h): the per-sensor
// health board, the LCM instance the raw bytes and NAV_IMAGE go out on, and the DeviceSources,
// bundled so the live mode (live_mode.h) wires them with a few lines:
//
//   NavdDevices devices(config, queue);   // after the queue, before the threads
//   devices.attach(publisher);            // health_t.sensors from the board
//   if (!replaying) devices.start(stop);  // one thread per non-sim sensor
//   ... stop.store(true); devices.join();
//
// Not in replay: a dive's config names the vehicle's devices, which must not be opened then.

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "nav/daemon/config/config.h"
#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/service/publisher.h"
#include "nav/daemon/sources/device_sources.h"
#include "nav/daemon/sources/sensor_health.h"

namespace lcm {
class LCM;
}

namespace nav::daemon::service {

class NavdDevices {
 public:
  /// Opens its own LCM at config.lcm.url for RAW_<NAME> / NAV_IMAGE (nothing is published if
  /// that fails; the threads still decode and push).
  NavdDevices(const daemon::NavdConfig& config, daemon::MeasurementQueue& queue);
  ~NavdDevices();
  /// Publishes the board in the publisher's health_t (call before the publisher runs).
  void attach(Publisher& publisher) { publisher.set_sensor_health(&health_); }
  /// Starts the device threads; returns how many (0 when every sensor is `sim`).
  std::size_t start(const std::atomic<bool>& stop) { return sources_->start(stop); }
  void join() { sources_->join(); }
  /// Joins the threads that end by `deadline`; the names of those left running (stuck in a
  /// device call, e.g. Aravis GVCP to a vanished camera). After a non-empty return this object
  /// must never be destroyed (its destructor would wait for them): the caller ends the process.
  std::vector<std::string> join_until(std::chrono::steady_clock::time_point deadline) {
    return sources_->join_until(deadline);
  }
  daemon::SensorHealthBoard& health() { return health_; }
  const daemon::RealtimeTally& realtime() const { return sources_->realtime(); }

 private:
  daemon::SensorHealthBoard health_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<daemon::DeviceSources> sources_;
};

}  // namespace nav::daemon::service
