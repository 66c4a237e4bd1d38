#include "nav/daemon/log/dive_log.h"

#include <lcm/lcm-cpp.hpp>

#include <cctype>
#include <vector>

namespace nav::daemon {
namespace {

template <class Msg>
Msg decode_as(const lcm::LogEvent& event, const std::string& path) {
  Msg msg;
  if (msg.decode(event.data, 0, event.datalen) != event.datalen) {
    throw DiveLogError(path + ": event " + std::to_string(event.eventnum) + " on channel " +
                       event.channel + " does not decode as " + Msg::getTypeName());
  }
  return msg;
}

template <class Msg>
void encode_into(const Msg& msg, std::vector<std::uint8_t>& buffer) {
  buffer.resize(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
}

}  // namespace

std::string raw_channel(std::string_view sensor_name) {
  std::string channel(kRawChannelPrefix);
  for (char c : sensor_name) {
    channel += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  return channel;
}

DiveLogWriter::DiveLogWriter(const std::string& path) : path_(path) {
  log_ = new lcm::LogFile(path, "w");
  if (!log_->good()) {
    delete log_;
    log_ = nullptr;
    throw DiveLogError(path + ": cannot create the dive log");
  }
}

DiveLogWriter::~DiveLogWriter() { delete log_; }

void DiveLogWriter::write_event(const std::string& channel, std::int64_t utime,
                                const void* data, int size) {
  if (utime < last_utime_) {
    throw DiveLogError(path_ + ": event " + std::to_string(events_) + " on " + channel +
                       " goes back in time (" + std::to_string(utime) + " < " +
                       std::to_string(last_utime_) + " us)");
  }
  lcm::LogEvent event{};
  event.timestamp = utime;
  event.channel = channel;
  event.datalen = size;
  event.data = const_cast<void*>(data);
  if (log_->writeEvent(&event) != 0) {
    throw DiveLogError(path_ + ": write failed at event " + std::to_string(events_));
  }
  last_utime_ = utime;
  ++events_;
}

void DiveLogWriter::write_raw(std::string_view sensor_name, std::int64_t host_realtime_us,
                              std::int64_t host_monotonic_us,
                              std::span<const std::uint8_t> bytes) {
  navlcm::raw_bytes_t msg;
  msg.utime = host_realtime_us;
  msg.host_monotonic_us = host_monotonic_us;
  msg.device = std::string(sensor_name);
  msg.num_bytes = static_cast<std::int32_t>(bytes.size());
  msg.data.assign(bytes.begin(), bytes.end());
  std::vector<std::uint8_t> buffer;
  encode_into(msg, buffer);
  write_event(raw_channel(sensor_name), msg.utime, buffer.data(),
              static_cast<int>(buffer.size()));
}

void DiveLogWriter::write(const navlcm::image_metadata_t& image) {
  std::vector<std::uint8_t> buffer;
  encode_into(image, buffer);
  write_event(std::string(kImageChannel), image.utime, buffer.data(),
              static_cast<int>(buffer.size()));
}

void DiveLogWriter::write(const navlcm::registration_t& registration) {
  std::vector<std::uint8_t> buffer;
  encode_into(registration, buffer);
  write_event(std::string(kRegistrationChannel), registration.utime, buffer.data(),
              static_cast<int>(buffer.size()));
}

DiveLogReader::DiveLogReader(const std::string& path) : path_(path) {
  log_ = new lcm::LogFile(path, "r");
  if (!log_->good()) {
    delete log_;
    log_ = nullptr;
    throw DiveLogError(path + ": cannot open the dive log");
  }
}

DiveLogReader::~DiveLogReader() { delete log_; }

std::optional<DiveLogEvent> DiveLogReader::next() {
  while (const lcm::LogEvent* event = log_->readNextEvent()) {
    ++events_;
    if (event->channel.rfind(kRawChannelPrefix, 0) == 0) {
      return decode_as<navlcm::raw_bytes_t>(*event, path_);
    }
    if (event->channel == kImageChannel) return decode_as<navlcm::image_metadata_t>(*event, path_);
    if (event->channel == kRegistrationChannel) {
      return decode_as<navlcm::registration_t>(*event, path_);
    }
    ++skipped_;
  }
  return std::nullopt;
}

}  // namespace nav::daemon
