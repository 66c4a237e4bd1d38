#pragma once
// The host's wall clock (CLOCK_REALTIME) against CLOCK_MONOTONIC (docs/faults.md, the
// clock_step scenarios). navd orders and dates measurements by CLOCK_MONOTONIC; CLOCK_REALTIME
// only stamps what leaves it (LCM utimes, the dive log's event times, the signature window).
//
// WallClockJumpMonitor: realtime - monotonic is constant except when the wall clock is stepped
// (settimeofday(2), an NTP/chrony step, a VM resume) or slewed (adjtime(3): at most 500 ppm,
// the kernel's limit, adjtimex(2)). A change larger than `threshold_us` plus the slew the
// elapsed monotonic time allows is a jump; its size is the change.
//
// ClockOffsetFile: navd's debugging / HIL seam for such a step without stepping the host's
// clock (shared by every process and container; Linux time namespaces offset only
// CLOCK_MONOTONIC and CLOCK_BOOTTIME, time_namespaces(7)). A thread reads `path` every
// `poll_period` and sets drivers::set_realtime_offset_us() (nav/drivers/time/timestamps.h) to
// the decimal number of seconds it holds; a missing or empty file is offset 0, a malformed one
// keeps the previous offset and is logged once.
//
// Threads: WallClockJumpMonitor has one owner (navd's publisher thread). ClockOffsetFile owns
// its thread; construct and destroy on one thread.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>

namespace nav::daemon {

class WallClockJumpMonitor {
 public:
  explicit WallClockJumpMonitor(std::int64_t threshold_us = 100'000)
      : threshold_us_(threshold_us) {}

  /// One reading of both clocks (µs). The jump of realtime - monotonic since the previous
  /// reading when it exceeds the threshold (and the allowed slew), else nullopt; the first
  /// reading only sets the reference.
  std::optional<std::int64_t> update(std::int64_t monotonic_us, std::int64_t realtime_us);

  int jumps() const { return jumps_; }
  std::int64_t last_jump_us() const { return last_jump_us_; }

 private:
  std::int64_t threshold_us_;
  std::optional<std::int64_t> last_offset_us_, last_monotonic_us_;
  int jumps_ = 0;
  std::int64_t last_jump_us_ = 0;
};

/// The offset file's content in µs: "" (or whitespace) is 0; nullopt when it is not one decimal
/// number of seconds within +-1e6 s.
std::optional<std::int64_t> parse_clock_offset_us(const std::string& text);

class ClockOffsetFile {
 public:
  explicit ClockOffsetFile(std::filesystem::path path,
                           std::chrono::milliseconds poll_period = std::chrono::milliseconds(100));
  ~ClockOffsetFile();
  ClockOffsetFile(const ClockOffsetFile&) = delete;
  ClockOffsetFile& operator=(const ClockOffsetFile&) = delete;

  /// Reads the file once now and applies it (the thread does this every poll period).
  void poll();

 private:
  std::filesystem::path path_;
  std::chrono::milliseconds poll_period_;
  std::string last_bad_text_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace nav::daemon
