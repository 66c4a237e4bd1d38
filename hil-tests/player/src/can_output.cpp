// CanOutput: candump log lines -> SocketCAN frames; see can_output.h.
#include "can_output.h"

#include <chrono>
#include <string_view>

#include "nav/drivers/codecs/candump_log.h"

namespace nav::hil {
namespace {

drivers::CanFrame to_frame(const drivers::CanLogFrame& logged) {
  drivers::CanFrame frame;
  frame.id = logged.id;
  frame.extended = logged.extended;
  frame.remote = logged.remote;
  frame.dlc = logged.dlc;
  frame.data = logged.data;
  return frame;
}

}  // namespace

std::string CanOutput::open(const std::string& interface) {
  auto bus = std::make_unique<drivers::SocketCanBus>();
  if (drivers::IoStatus s = bus->open_interface(interface); !s.ok()) return s.message();
  bus_ = std::move(bus);
  return {};
}

void CanOutput::write(std::span<const std::uint8_t> bytes, PlayedSensor& sensor) {
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  std::size_t begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(begin, end - begin);
    begin = end + 1;
    drivers::CanLogFrame logged;
    bool has_time = false;
    const drivers::CandumpLineResult r = drivers::parse_candump_line(line, logged, has_time);
    if (r == drivers::CandumpLineResult::kBlank) continue;
    if (r != drivers::CandumpLineResult::kFrame || !bus_ ||
        !bus_->send(to_frame(logged), std::chrono::milliseconds(10)).ok()) {
      ++sensor.dropped_frames;
      continue;
    }
    sensor.bytes += logged.dlc;
  }
}

}  // namespace nav::hil
