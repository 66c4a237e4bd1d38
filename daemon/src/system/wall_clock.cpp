// Wall clock jumps and the realtime offset seam; see nav/daemon/system/wall_clock.h.
#include "nav/daemon/system/wall_clock.h"

#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "nav/daemon/system/host_clock.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::daemon {
namespace {

/// adjtime(3)'s largest slew: 500 µs per second (adjtimex(2), MAXPHASE / MAXFREQ).
constexpr double kMaxSlewPerSecond = 500e-6;
constexpr double kMaxOffsetS = 1e6;

}  // namespace

std::optional<std::int64_t> WallClockJumpMonitor::update(std::int64_t monotonic_us,
                                                         std::int64_t realtime_us) {
  const std::int64_t offset = realtime_us - monotonic_us;
  std::optional<std::int64_t> jump;
  if (last_offset_us_) {
    const std::int64_t change = offset - *last_offset_us_;
    const double slew_us =
        kMaxSlewPerSecond * static_cast<double>(monotonic_us - *last_monotonic_us_);
    if (std::abs(static_cast<double>(change)) > static_cast<double>(threshold_us_) + slew_us) {
      jump = change;
      ++jumps_;
      last_jump_us_ = change;
    }
  }
  last_offset_us_ = offset;
  last_monotonic_us_ = monotonic_us;
  return jump;
}

std::optional<std::int64_t> parse_clock_offset_us(const std::string& text) {
  std::istringstream in(text);
  double seconds = 0.0;
  if (!(in >> seconds)) {
    in.clear();
    std::string rest;
    in >> rest;
    if (rest.empty()) return 0;  // empty or blank: no offset
    return std::nullopt;
  }
  std::string rest;
  if (in >> rest) return std::nullopt;  // trailing text
  if (!std::isfinite(seconds) || std::abs(seconds) > kMaxOffsetS) return std::nullopt;
  return std::llround(seconds * 1e6);
}

ClockOffsetFile::ClockOffsetFile(std::filesystem::path path, std::chrono::milliseconds poll_period)
    : path_(std::move(path)), poll_period_(poll_period) {
  poll();
  thread_ = std::thread([this] {
    while (sleep_until_monotonic_us(monotonic_us() + poll_period_.count() * 1000, stop_)) poll();
  });
}

ClockOffsetFile::~ClockOffsetFile() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

void ClockOffsetFile::poll() {
  std::string text;
  if (std::ifstream in(path_); in) {
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  const std::optional<std::int64_t> offset = parse_clock_offset_us(text);
  if (!offset) {
    if (text != last_bad_text_) {
      spdlog::warn(
          "navd: clock offset file {}: '{}' is not a number of seconds within +-1e6 s; "
          "the realtime offset stays {} us",
          path_.string(), text, drivers::realtime_offset_us());
    }
    last_bad_text_ = text;
    return;
  }
  last_bad_text_.clear();
  drivers::set_realtime_offset_us(*offset);
}

}  // namespace nav::daemon
