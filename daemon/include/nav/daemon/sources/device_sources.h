#pragma once
// navd's device threads: one per configured sensor with a hardware transport (serial, can,
// gige, v4l2; `sim` sensors have none), built from the config and run with the loops of
// device_source.h and camera_source.h. Each thread is named navd-<sensor> (cut to 15 bytes);
// serial and CAN threads run under SCHED_FIFO at config.realtime.device_priority when set.
// Owns the transports, decoders, producers and threads.
//
// Usage (navd main): construct after the MeasurementQueue and the SensorHealthBoard, start(stop),
// ..., set stop, join(). Raw bytes and NAV_IMAGE are published on `lcm` (may be null).
// Threads: start()/join() from one thread (main); the device threads only touch their own
// objects, the queue (their producer) and their SensorHealth entry.

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "nav/daemon/config/config.h"
#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/sources/device_source.h"
#include "nav/daemon/sources/sensor_health.h"
#include "nav/daemon/system/realtime.h"

namespace nav::daemon {

/// True when the sensor reads a device (its transport is not `sim`).
bool has_device(const SensorConfig& sensor);

struct DeviceSourcesOptions {
  DeviceLoopOptions loop;
  int thumbnail_width_px = 160;
};

class DeviceSources {
 public:
  DeviceSources(const NavdConfig& config, MeasurementQueue& queue, lcm::LCM* lcm,
                SensorHealthBoard& health, DeviceSourcesOptions options = {});
  ~DeviceSources();  ///< joins (stop must have been set)
  DeviceSources(const DeviceSources&) = delete;
  DeviceSources& operator=(const DeviceSources&) = delete;

  /// Starts one thread per sensor with a device; returns how many.
  std::size_t start(const std::atomic<bool>& stop);
  void join();
  /// Joins the threads that return by `deadline` (stop must have been set) and detaches the
  /// others, whose sensor names it returns: a thread stuck in a device call that cannot be
  /// interrupted (an Aravis GVCP transaction to a vanished or hung GigE camera blocks 2.5-5 s,
  /// several in a row at stop: apps/navd/README.md). After a non-empty return this object,
  /// the queue, the LCM and the health board must stay alive until the process ends: the caller
  /// ends it (navd: std::_Exit after its final checkpoint and log lines).
  std::vector<std::string> join_until(std::chrono::steady_clock::time_point deadline);
  std::size_t size() const { return threads_.size(); }
  const LcmRawPublisher& publisher() const { return publisher_; }
  /// The serial and CAN threads' SCHED_FIFO requests (config.realtime.device_priority).
  const RealtimeTally& realtime() const { return realtime_; }

 private:
  struct Device;
  void run(Device& device, const std::atomic<bool>& stop);

  const NavdConfig& config_;
  MeasurementQueue& queue_;
  SensorHealthBoard& health_;
  DeviceSourcesOptions options_;
  LcmRawPublisher publisher_;
  std::vector<std::unique_ptr<Device>> devices_;
  RealtimeTally realtime_;
  std::vector<std::thread> threads_;
};

}  // namespace nav::daemon
