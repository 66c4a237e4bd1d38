#pragma once
// The host clocks in microseconds: CLOCK_MONOTONIC (what measurements are stamped with on
// receipt, pacing) and CLOCK_REALTIME (LCM utimes).
#include <cstdint>
#include <ctime>

namespace nav::daemon {

inline std::int64_t clock_us(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000 + ts.tv_nsec / 1000;
}
inline std::int64_t monotonic_us() { return clock_us(CLOCK_MONOTONIC); }
inline std::int64_t realtime_us() { return clock_us(CLOCK_REALTIME); }

}  // namespace nav::daemon
