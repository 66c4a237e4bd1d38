#pragma once
// The dive-log source: plays a recorded dive (dive_log.h) into the MeasurementQueue exactly as
// the driver threads would on the vehicle: each RAW_<NAME> message goes through the sensor's
// decoder (sensor_decoder.h, the same codecs) and NAV_IMAGE becomes an ImageEvent.
// Registrations (NAV_REGISTRATION) are not measurements: load_registrations() reads them all
// before the replay starts (the vision stage's stand-in, registration_table.h).
//
// Pacing: `speed` x real time on the log's host monotonic clock, or as fast as possible; in the
// latter mode the source waits while the queue is more than half full (a replay may throttle; a
// live driver would drop).
//
// Times: a RAW_* message is fed to its decoder with its own host times (utime = realtime,
// host_monotonic_us), so measurements get exactly the validity they had on the vehicle. A
// NAV_IMAGE becomes an ImageEvent valid at time_of_validity_us (monotonic), host_realtime =
// utime, host_monotonic = utime minus the realtime - monotonic offset of the latest RAW_*
// message (validity when none was seen yet), sensor_index = the config's first camera. Pacing
// uses each event's monotonic time (RAW_*: host_monotonic_us; NAV_IMAGE: that host time).
// A RAW_* message is matched to the config sensor whose name equals its `device` (then,
// ignoring case, the channel suffix); others are counted in unknown_devices, not fatal.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "nav/daemon/config/config.h"
#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/filter/registration_message.h"
#include "nav/core/navigation/registration_table.h"
#include "nav/daemon/sources/sensor_decoder.h"

namespace nav::daemon {

struct DiveLogSourceOptions {
  double speed = 1.0;  ///< x real time (> 0); ignored when as_fast_as_possible
  bool as_fast_as_possible = false;
};

struct DiveLogSourceCounters {
  std::uint64_t events = 0;           ///< log events read
  std::uint64_t raw_messages = 0;     ///< RAW_* messages fed to decoders
  std::uint64_t unknown_devices = 0;  ///< RAW_* from a sensor name not in the config
  std::uint64_t measurements = 0;     ///< pushed to the queue (images included)
  std::uint64_t images = 0;
  std::uint64_t decode_errors = 0;                             ///< summed over the decoders
  std::int64_t first_monotonic_us = 0, last_monotonic_us = 0;  ///< log's host time span
  std::uint64_t queue_drops = 0;            ///< pushes refused by a full queue (paced mode only)
  std::uint64_t images_without_camera = 0;  ///< NAV_IMAGE while the config has no camera
  std::uint64_t registrations = 0;          ///< NAV_REGISTRATION events (read, not pushed)
  /// Per config sensor (index as in NavdConfig::sensors; cameras stay zero).
  std::vector<SensorDecoderCounters> sensors;
};

/// Reads every NAV_REGISTRATION of the log. Throws DiveLogError.
RegistrationTable load_registrations(const std::string& log_path);

/// Runs on its own thread; returns at the end of the log or when `stop` is set, setting `done`
/// after the last push. Throws DiveLogError on a corrupt log.
DiveLogSourceCounters run_dive_log_source(const std::string& log_path, const NavdConfig& config,
                                          const DiveLogSourceOptions& options,
                                          MeasurementQueue& queue, const std::atomic<bool>& stop,
                                          std::atomic<bool>& done);

}  // namespace nav::daemon
