#pragma once
// A CAN signal table (can_signals.h, usually loaded by can_config.h) applied to frames from the
// CanBus transport, with one ClockMapping per message that carries a time-of-validity counter:
// what a CAN sensor driver thread runs per received frame.
//
// Host time of a frame: CLOCK_MONOTONIC (navd orders measurements on it). When the socket gave
// a kernel receive stamp (CLOCK_REALTIME, closer to the bus than the read), it is moved onto
// the monotonic clock by the (realtime - monotonic) difference sampled at the read; a kernel
// stamp later than the read or more than one second before it is ignored.
// Time of validity: the message's sensor time mapped onto that monotonic host clock, with the
// counter period taken from the time signal (2^length steps of its unit).

#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "nav/drivers/codecs/can_signals.h"
#include "nav/drivers/time/clock_mapping.h"
#include "nav/drivers/transports/can_bus.h"

namespace nav::drivers {

class CanFrameDecoder {
 public:
  /// `clock` is the template for every message's mapping (its sensor_modulus_us is replaced
  /// by the time signal's period). Throws std::invalid_argument for an invalid table.
  explicit CanFrameDecoder(std::vector<CanMessageSpec> messages, ClockMappingOptions clock = {});

  /// Decodes one frame into `out`; false (and counted in stats()) when it is not decoded;
  /// remote frames count as unsupported. out.time.host.monotonic_us is the host time above.
  bool decode(const CanFrame& frame, CanDecodedMessage& out);
  /// Monotonic host time of validity of the message decoded last (its sensor time through
  /// the message's clock mapping, which the decode updated; for a message dated by another
  /// (time_from), through that message's mapping); nullopt when the message has no valid
  /// sensor time or the mapping is not initialised yet.
  std::optional<int64_t> time_of_validity_us() const { return time_of_validity_us_; }

  /// Clock mapping of a message with a time signal, nullptr otherwise.
  const ClockMapping* clock(const CanMessageSpec& message) const;
  const CanSignalDecoder& signals() const { return decoder_; }
  const DecodeStats& stats() const { return stats_; }

 private:
  CanSignalDecoder decoder_;
  std::map<const CanMessageSpec*, std::unique_ptr<ClockMapping>> clocks_;
  std::optional<int64_t> time_of_validity_us_;
  uint64_t remote_frames_ = 0;
  DecodeStats stats_;  ///< the signal decoder's counters plus remote frames as unsupported
};

/// CLOCK_MONOTONIC time of a frame (see the file comment).
int64_t can_frame_monotonic_us(const CanFrame& frame);

}  // namespace nav::drivers
