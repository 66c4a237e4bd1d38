#pragma once
// The host clocks in microseconds: CLOCK_MONOTONIC (what measurements are stamped with on
// receipt, pacing) and CLOCK_REALTIME (LCM utimes) plus the process's realtime offset
// (nav/drivers/time/timestamps.h: 0 unless navd's --clock-offset-file sets it), and a
// stoppable sleep on the monotonic one.
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <ctime>

#include "nav/drivers/time/timestamps.h"

namespace nav::daemon {

inline std::int64_t clock_us(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000 + ts.tv_nsec / 1000;
}
inline std::int64_t monotonic_us() { return clock_us(CLOCK_MONOTONIC); }
inline std::int64_t realtime_us() {
  return clock_us(CLOCK_REALTIME) + drivers::realtime_offset_us();
}

/// Sleeps until host monotonic time `until_us`, in 50 ms slices so that `stop` is seen within
/// 50 ms; returns false if `stop` was set.
inline bool sleep_until_monotonic_us(std::int64_t until_us, const std::atomic<bool>& stop) {
  constexpr std::int64_t kSliceUs = 50'000;
  for (std::int64_t now = monotonic_us(); now < until_us && !stop.load(); now = monotonic_us()) {
    const std::int64_t wake = std::min(until_us, now + kSliceUs);
    const timespec ts{static_cast<time_t>(wake / 1'000'000),
                      static_cast<long>((wake % 1'000'000) * 1000)};
    ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
  }
  return !stop.load();
}

}  // namespace nav::daemon
