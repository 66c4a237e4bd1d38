#pragma once
// Dive logs: a standard LCM log file (lcm-logger compatible) holding what the vehicle's sensors
// produced, so a dive can be replayed through the same codecs and filter as on the vehicle.
// Layout of a dive directory and the channels: hil-tests/README.md.
//
//   RAW_<NAME>        navlcm::raw_bytes_t      bytes as read from sensor <name> (config name,
//                                              upper-cased in the channel; `device` keeps it)
//   NAV_IMAGE         navlcm::image_metadata_t one per camera frame
//   NAV_REGISTRATION  navlcm::registration_t   image registration results (vision or oracle)
//
// The log event timestamp is the message's utime (host CLOCK_REALTIME, µs). Writers must write
// events in non-decreasing timestamp order (DiveLogWriter checks and throws).

#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>

#include <navlcm/image_metadata_t.hpp>
#include <navlcm/raw_bytes_t.hpp>
#include <navlcm/registration_t.hpp>

namespace lcm {
class LogFile;
}

namespace nav::daemon {

inline constexpr std::string_view kRawChannelPrefix = "RAW_";
inline constexpr std::string_view kImageChannel = "NAV_IMAGE";
inline constexpr std::string_view kRegistrationChannel = "NAV_REGISTRATION";

/// "RAW_" + upper-cased sensor name ("dvl" -> "RAW_DVL").
std::string raw_channel(std::string_view sensor_name);

/// An error reading or writing a dive log; what() names the file and the event number.
class DiveLogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class DiveLogWriter {
 public:
  /// Creates (truncates) the file. Throws DiveLogError if it cannot.
  explicit DiveLogWriter(const std::string& path);
  ~DiveLogWriter();
  DiveLogWriter(const DiveLogWriter&) = delete;
  DiveLogWriter& operator=(const DiveLogWriter&) = delete;

  void write_raw(std::string_view sensor_name, std::int64_t host_realtime_us,
                 std::int64_t host_monotonic_us, std::span<const std::uint8_t> bytes);
  void write(const navlcm::image_metadata_t& image);
  void write(const navlcm::registration_t& registration);
  /// Any LCM message on any channel (e.g. navd's own outputs); timestamp = utime.
  void write_event(const std::string& channel, std::int64_t utime, const void* data, int size);

  std::int64_t events_written() const { return events_; }

 private:
  std::string path_;
  lcm::LogFile* log_ = nullptr;
  std::int64_t events_ = 0;
  std::int64_t last_utime_ = INT64_MIN;
};

/// One decoded event of a dive log. Channels navd does not know are skipped by next().
using DiveLogEvent =
    std::variant<navlcm::raw_bytes_t, navlcm::image_metadata_t, navlcm::registration_t>;

class DiveLogReader {
 public:
  /// Opens for reading. Throws DiveLogError if the file is missing or not an LCM log.
  explicit DiveLogReader(const std::string& path);
  ~DiveLogReader();
  DiveLogReader(const DiveLogReader&) = delete;
  DiveLogReader& operator=(const DiveLogReader&) = delete;

  /// The next known event, or nullopt at the end. A message that does not decode as its
  /// channel's type throws DiveLogError naming the channel and event number.
  std::optional<DiveLogEvent> next();

  std::int64_t events_read() const { return events_; }
  std::int64_t events_skipped() const { return skipped_; }

 private:
  std::string path_;
  lcm::LogFile* log_ = nullptr;
  std::int64_t events_ = 0;
  std::int64_t skipped_ = 0;
};

}  // namespace nav::daemon
