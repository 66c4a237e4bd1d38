#pragma once
// CAN side of the playback (dive_player.h): a CAN sensor's RAW_<NAME> bytes are candump log
// lines, one per frame (daemon sources/sensor_decoder.h); each becomes a frame sent on a
// SocketCAN interface (vcan0 on a bench without the vehicle's bus).

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "nav/drivers/transports/can_bus.h"
#include "nav/hil/dive_player.h"

namespace nav::hil {

class CanOutput {
 public:
  /// Opens `interface`; "" on success, else why not (e.g. the kernel has no PF_CAN).
  std::string open(const std::string& interface);
  bool is_open() const { return bus_ != nullptr; }
  /// Sends every candump line of `bytes`; counts into `sensor` (bytes sent, frames dropped).
  void write(std::span<const std::uint8_t> bytes, PlayedSensor& sensor);

 private:
  std::unique_ptr<drivers::SocketCanBus> bus_;
};

}  // namespace nav::hil
