// CAN signal table applied to transport frames, with per-message clock mappings; see
// can_frame_decoder.h.
#include "nav/drivers/config/can_frame_decoder.h"

#include <stdexcept>
#include <utility>

namespace nav::drivers {

int64_t can_frame_monotonic_us(const CanFrame& frame) {
  if (frame.kernel_realtime_us) {
    const int64_t before_read_us = frame.received.realtime_us - *frame.kernel_realtime_us;
    if (before_read_us >= 0 && before_read_us <= 1'000'000) {
      return frame.received.monotonic_us - before_read_us;
    }
  }
  return frame.received.monotonic_us;
}

CanFrameDecoder::CanFrameDecoder(std::vector<CanMessageSpec> messages, ClockMappingOptions clock)
    : decoder_(std::move(messages)) {
  for (const CanMessageSpec& m : decoder_.messages()) {
    for (const CanSignalSpec& s : m.signals) {
      if (!s.time_of_validity) continue;
      ClockMappingOptions o = clock;
      o.sensor_modulus_us = can_time_signal_modulus_us(s).value_or(0);
      o.sensor_resolution_us = can_time_signal_resolution_us(s);
      if (o.sensor_modulus_us > 0 && o.jump_threshold_us >= o.sensor_modulus_us / 2) {
        o.jump_threshold_us = o.sensor_modulus_us / 4;  // short counters, e.g. 16-bit ms
      }
      if (std::string err = o.validate(); !err.empty()) {
        throw std::invalid_argument("CAN message \"" + m.name + "\" time signal \"" + s.name +
                                    "\": ClockMappingOptions." + err);
      }
      clocks_.emplace(&m, std::make_unique<ClockMapping>(o));
    }
  }
}

const ClockMapping* CanFrameDecoder::clock(const CanMessageSpec& message) const {
  const auto it = clocks_.find(&message);
  return it == clocks_.end() ? nullptr : it->second.get();
}

bool CanFrameDecoder::decode(const CanFrame& frame, CanDecodedMessage& out) {
  time_of_validity_us_.reset();
  if (frame.remote) {
    ++remote_frames_;
    ++stats_.unsupported;
    return false;
  }
  const int64_t realtime_us = frame.kernel_realtime_us.value_or(frame.received.realtime_us);
  const Timestamps time{HostTime{can_frame_monotonic_us(frame), realtime_us}, std::nullopt};
  const uint8_t length = frame.dlc <= 8 ? frame.dlc : 8;
  const bool ok = decoder_.decode(frame.id, frame.extended, {frame.data.data(), length}, time, out);
  stats_ = decoder_.stats();
  stats_.unsupported += remote_frames_;
  if (!ok || !out.time.sensor_time_us) return ok;
  // A message dated by another (time_from) is mapped with that message's clock, which only
  // its own samples update.
  const bool linked = !out.spec->time_from.empty();
  const auto it = clocks_.find(linked ? decoder_.find(out.spec->time_from) : out.spec);
  if (it == clocks_.end()) return ok;
  ClockMapping& clock = *it->second;
  int64_t sensor_us = *out.time.sensor_time_us;
  const int64_t modulus = clock.options().sensor_modulus_us;
  if (modulus > 0) sensor_us = ((sensor_us % modulus) + modulus) % modulus;
  if (!linked) clock.update(sensor_us, time.host.monotonic_us);
  time_of_validity_us_ = clock.to_host_us(sensor_us);
  return ok;
}

}  // namespace nav::drivers
