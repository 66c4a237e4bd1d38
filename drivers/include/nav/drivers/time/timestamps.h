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

/// The host realtime seam (docs/faults.md "clock_step"): every CLOCK_REALTIME this process reads
/// through host_time_now() (and navd's daemon::realtime_us(), and the arrival stamps the camera
/// back ends take from the kernel's realtime clock) is the kernel's plus this offset, so a HIL
/// test can step navd's wall clock without stepping the host's, which other processes share.
/// 0 unless set; CLOCK_MONOTONIC is never offset. Atomic: any thread may set or read it.
void set_realtime_offset_us(int64_t offset_us);
int64_t realtime_offset_us();

}  // namespace nav::drivers
