// Host receive time stamps (docs/architecture.md "Time"): CLOCK_MONOTONIC and CLOCK_REALTIME read
// with clock_gettime(2) (POSIX.1-2017) right after a transport returns bytes.

#include <atomic>
#include <ctime>

#include "nav/drivers/time/timestamps.h"

namespace nav::drivers {
namespace {
int64_t read_us(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1'000;
}
std::atomic<int64_t> g_realtime_offset_us{0};
}  // namespace

HostTime host_time_now() {
  return {read_us(CLOCK_MONOTONIC),
          read_us(CLOCK_REALTIME) + g_realtime_offset_us.load(std::memory_order_relaxed)};
}

void set_realtime_offset_us(int64_t offset_us) {
  g_realtime_offset_us.store(offset_us, std::memory_order_relaxed);
}

int64_t realtime_offset_us() { return g_realtime_offset_us.load(std::memory_order_relaxed); }

}  // namespace nav::drivers
