#pragma once
// The player's interruptible sleep on the daemon's host clock (nav/daemon/host_clock.h:
// CLOCK_MONOTONIC, what navd stamps its reads with). The clocks themselves are the daemon's; this
// file holds only the sleep, until the daemon library offers one.
#include <time.h>

#include <algorithm>
#include <atomic>
#include <cstdint>

#include "nav/daemon/host_clock.h"

namespace nav::hil {

/// Sleeps until host monotonic `until_us`, in 50 ms slices so that `stop` is seen; false if
/// `stop` was set.
inline bool sleep_until_us(std::int64_t until_us, const std::atomic<bool>& stop) {
  constexpr std::int64_t kSliceUs = 50'000;
  for (std::int64_t now = daemon::monotonic_us(); now < until_us && !stop.load();
       now = daemon::monotonic_us()) {
    const std::int64_t wake = std::min(until_us, now + kSliceUs);
    const timespec ts{static_cast<time_t>(wake / 1'000'000),
                      static_cast<long>((wake % 1'000'000) * 1000)};
    ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
  }
  return !stop.load();
}

}  // namespace nav::hil
