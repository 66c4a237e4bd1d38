#pragma once
// Time stamps carried by every decoded value (docs/architecture.md "Time"): the sensor's own time
// of validity when its protocol has one, and the host receive times, all in microseconds.

#include <cstdint>
#include <optional>

namespace nav::drivers {

struct HostTime {
  int64_t monotonic_us = 0;  ///< CLOCK_MONOTONIC when the bytes were read
  int64_t realtime_us = 0;   ///< CLOCK_REALTIME (UNIX epoch) when the bytes were read
};

struct Timestamps {
  HostTime host;                          ///< when the host received the record
  std::optional<int64_t> sensor_time_us;  ///< sensor's time of validity, its own clock/epoch
};

/// Reads CLOCK_MONOTONIC and CLOCK_REALTIME now (host side only; never used inside codecs,
/// which take HostTime as an argument so that replay and tests are deterministic).
HostTime host_time_now();

}  // namespace nav::drivers
