// Wall clock: the jump monitor on synthetic readings (steady, slewing at the kernel's limit,
// stepped +-2 s), the offset file's parser, the seam itself (daemon::realtime_us() and
// drivers::host_time_now() against the kernel's CLOCK_REALTIME read here, CLOCK_MONOTONIC
// untouched), and the camera's time of validity when a step falls between a frame's arrival
// and its grab.
#include "nav/daemon/system/wall_clock.h"

#include <gtest/gtest.h>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <thread>

#include "nav/daemon/sources/camera_source.h"
#include "nav/daemon/system/host_clock.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::daemon {
namespace {

std::int64_t kernel_realtime_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000 + ts.tv_nsec / 1000;
}

/// Replaces `path` by a file holding `text` at once (rename(2)), so that the offset file's
/// thread never reads it half-written (an empty file is offset 0).
void write_file(const std::filesystem::path& path, const std::string& text) {
  const std::filesystem::path tmp = path.string() + ".tmp";
  std::ofstream(tmp, std::ios::trunc) << text;
  std::filesystem::rename(tmp, path);
}

/// Resets the process-wide offset whatever a test does.
struct OffsetGuard {
  ~OffsetGuard() { drivers::set_realtime_offset_us(0); }
};

TEST(WallClockJumpMonitor, SteadyAndSlewingClocksAreNoJump) {
  WallClockJumpMonitor m(100'000);
  const std::int64_t epoch = 1'700'000'000'000'000;
  EXPECT_FALSE(m.update(0, epoch));  // the reference
  for (int s = 1; s <= 100; ++s) {
    // adjtime's largest slew, 500 µs per second, for 100 s: 50 ms in all, never a jump.
    EXPECT_FALSE(m.update(s * 1'000'000LL, epoch + s * 1'000'000LL + s * 500)) << s;
  }
  EXPECT_EQ(m.jumps(), 0);
}

TEST(WallClockJumpMonitor, StepsOfPlusAndMinusTwoSecondsAreReportedWithTheirSize) {
  WallClockJumpMonitor m(100'000);
  const std::int64_t epoch = 1'700'000'000'000'000;
  (void)m.update(0, epoch);
  const auto plus = m.update(1'000'000, epoch + 1'000'000 + 2'000'000);
  ASSERT_TRUE(plus.has_value());
  EXPECT_EQ(*plus, 2'000'000);
  EXPECT_FALSE(m.update(2'000'000, epoch + 2'000'000 + 2'000'000));  // stays stepped: once
  const auto minus = m.update(3'000'000, epoch + 3'000'000);
  ASSERT_TRUE(minus.has_value());
  EXPECT_EQ(*minus, -2'000'000);
  EXPECT_EQ(m.jumps(), 2);
  EXPECT_EQ(m.last_jump_us(), -2'000'000);
  // Just above the threshold plus one second's slew (100 ms + 0.5 ms) is a jump, below is not.
  EXPECT_FALSE(m.update(4'000'000, epoch + 4'000'000 + 100'400));
  EXPECT_TRUE(m.update(5'000'000, epoch + 5'000'000 + 100'400 + 100'600));
}

TEST(ClockOffsetFile, ParsesSecondsAndRefusesAnythingElse) {
  EXPECT_EQ(parse_clock_offset_us(""), 0);
  EXPECT_EQ(parse_clock_offset_us(" \n"), 0);
  EXPECT_EQ(parse_clock_offset_us("2\n"), 2'000'000);
  EXPECT_EQ(parse_clock_offset_us("-2.5"), -2'500'000);
  EXPECT_EQ(parse_clock_offset_us("0.000001"), 1);
  EXPECT_FALSE(parse_clock_offset_us("two"));
  EXPECT_FALSE(parse_clock_offset_us("2 s"));
  EXPECT_FALSE(parse_clock_offset_us("nan"));
  EXPECT_FALSE(parse_clock_offset_us("2e7"));
}

TEST(ClockOffsetFile, StepsTheProcessRealtimeAloneAndFollowsTheFile) {
  OffsetGuard guard;
  const auto path = std::filesystem::temp_directory_path() /
                    ("wall_clock_test_" + std::to_string(::getpid()) + ".offset");
  std::filesystem::remove(path);
  ClockOffsetFile file(path, std::chrono::milliseconds(10));
  EXPECT_EQ(drivers::realtime_offset_us(), 0);  // missing file: no offset
  write_file(path, "2\n");
  file.poll();
  EXPECT_EQ(drivers::realtime_offset_us(), 2'000'000);
  const std::int64_t kernel_before = kernel_realtime_us();
  const std::int64_t navd = realtime_us();
  const drivers::HostTime host = drivers::host_time_now();
  const std::int64_t kernel_after = kernel_realtime_us();
  EXPECT_GE(navd, kernel_before + 2'000'000);
  EXPECT_LE(navd, kernel_after + 2'000'000);
  EXPECT_GE(host.realtime_us, kernel_before + 2'000'000);
  EXPECT_LE(host.realtime_us, kernel_after + 2'000'000);
  timespec mono{};
  clock_gettime(CLOCK_MONOTONIC, &mono);
  EXPECT_LE(
      std::abs(monotonic_us() - (std::int64_t{mono.tv_sec} * 1'000'000 + mono.tv_nsec / 1000)),
      100'000);  // monotonic is never offset
  // The thread picks a new value up within its poll period; a malformed file keeps it.
  write_file(path, "-2\n");
  for (int i = 0; i < 200 && drivers::realtime_offset_us() != -2'000'000; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_EQ(drivers::realtime_offset_us(), -2'000'000);
  write_file(path, "garbage");
  file.poll();
  EXPECT_EQ(drivers::realtime_offset_us(), -2'000'000);
  std::filesystem::remove(path);
}

TEST(CameraValidity, AStepBetweenArrivalAndGrabFallsBackToTheGrabTime) {
  const std::int64_t latency = 10'000;
  drivers::CameraFrame f;
  f.time.host.monotonic_us = 50'000'000;
  f.time.host.realtime_us = 1'700'000'000'000'000;  // realtime - monotonic at the grab
  const std::int64_t offset = f.time.host.realtime_us - f.time.host.monotonic_us;
  // No step: the arrival 3 ms before the grab, moved onto monotonic.
  f.arrival_realtime_us = f.time.host.realtime_us - 3'000;
  EXPECT_EQ(camera_validity_us(f, latency), 50'000'000 - 3'000 - latency);
  // The wall clock stepped +2 s between the arrival and the grab: the arrival (on the old
  // clock) would convert to 2 s before the grab, a frame navd would date 2 s early.
  f.arrival_realtime_us = (offset - 2'000'000) + 50'000'000 - 3'000;
  EXPECT_EQ(camera_validity_us(f, latency), 50'000'000 - latency);
  // Stepped -2 s: the arrival would convert to after the grab.
  f.arrival_realtime_us = (offset + 2'000'000) + 50'000'000 - 3'000;
  EXPECT_EQ(camera_validity_us(f, latency), 50'000'000 - latency);
  // No arrival stamp: the grab.
  f.arrival_realtime_us.reset();
  EXPECT_EQ(camera_validity_us(f, latency), 50'000'000 - latency);
}

}  // namespace
}  // namespace nav::daemon
