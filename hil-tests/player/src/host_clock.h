#pragma once
// The host clocks the player schedules on: CLOCK_MONOTONIC for the playback schedule (what
// navd stamps its reads with), CLOCK_REALTIME for LCM utimes, and an interruptible sleep.
#include <time.h>

#include <algorithm>
#include <atomic>
#include <cstdint>

namespace nav::hil {

inline std::int64_t clock_now_us(clockid_t clock) {
  timespec ts{};
  ::clock_gettime(clock, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}
inline std::int64_t monotonic_now_us() { return clock_now_us(CLOCK_MONOTONIC); }
inline std::int64_t realtime_now_us() { return clock_now_us(CLOCK_REALTIME); }

/// Sleeps until host monotonic `until_us`, in 50 ms slices so that `stop` is seen; false if
/// `stop` was set.
inline bool sleep_until_us(std::int64_t until_us, const std::atomic<bool>& stop) {
  constexpr std::int64_t kSliceUs = 50'000;
  for (std::int64_t now = monotonic_now_us(); now < until_us && !stop.load();
       now = monotonic_now_us()) {
    const std::int64_t wake = std::min(until_us, now + kSliceUs);
    const timespec ts{static_cast<time_t>(wake / 1'000'000),
                      static_cast<long>((wake % 1'000'000) * 1000)};
    ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
  }
  return !stop.load();
}

}  // namespace nav::hil
