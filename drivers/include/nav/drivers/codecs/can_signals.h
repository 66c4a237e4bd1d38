#pragma once
// CAN signal decoding with the DBC model (Vector "DBC File Format Documentation", SG_ lines):
// each message (frame id, standard/extended, DLC, optional multiplexer switch) carries signals
// laid out by start bit, length, byte order, signedness, then physical = raw * scale + offset
// in the configured unit, converted here to SI (deg -> rad, mm/s -> m/s, ms -> s, ...).
//
// Bit numbering (the classic trap), as in the DBC format, CANdb++ and cantools: bit b of the
// payload is bit (b % 8) of byte (b / 8), LSB first, for BOTH byte orders.
//  * Intel / little-endian (`@1`): start_bit names the LEAST significant bit; the signal
//    occupies bits start_bit .. start_bit + length - 1 in that numbering (a linear LSB-first
//    field across bytes).
//  * Motorola / big-endian (`@0`): start_bit names the MOST significant bit; the following
//    bits descend within the byte (bit 7 -> 0) and continue at bit 7 of the NEXT byte (the
//    "sawtooth"). E.g. 7|16@0 is a big-endian u16 in bytes 0..1; 0|12@0 takes bit 0 of
//    byte 0, all of byte 1 and bits 7..5 of byte 2 (cantools' motohawk.dbc example:
//    Temperature 250.1 degK, AverageRadius 3.2 m, Enable 1 encode to c0 01 40 00 00 00 00 00).
//
// Pure: no I/O, no clocks, no allocation while decoding once the output was sized.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "nav/drivers/codecs/decode_stats.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::drivers {

enum class CanByteOrder { kIntel, kMotorola };

/// How a configured unit maps to SI: si = value * factor + offset.
struct CanUnitConversion {
  double factor = 1.0;
  double offset = 0.0;
  std::string_view si_unit;  ///< "m", "m/s", "rad", "rad/s", "s", "Pa", "degC", "1", ...
};

/// SI conversion of a unit name accepted in CAN configs ("deg", "deg/s", "mm/s", "cm", "ms",
/// "us", "dbar", "" or "1" for dimensionless, ...); nullopt for an unknown unit.
std::optional<CanUnitConversion> can_unit_to_si(std::string_view unit);

/// One signal (DBC SG_ line). Physical value in `unit` = raw * scale + offset; range checks
/// apply to that physical value (before the SI conversion), as in DBC.
struct CanSignalSpec {
  std::string name;
  uint32_t start_bit = 0;  ///< DBC numbering (see file comment), 0..63
  uint32_t length = 1;     ///< bits, 1..64
  CanByteOrder byte_order = CanByteOrder::kIntel;
  bool is_signed = false;  ///< two's complement raw value
  double scale = 1.0;      ///< DBC factor, must be non-zero
  double offset = 0.0;
  std::optional<double> min;  ///< physical range in `unit`; a value outside is rejected
  std::optional<double> max;
  std::string unit;  ///< configured unit (see can_unit_to_si)
  /// Raw bit pattern (the low `length` bits) meaning "no valid value" (e.g. 0x8000).
  std::optional<uint64_t> invalid_raw;
  /// Present only when the message's multiplexer switch has this value (DBC `m<N>`).
  std::optional<uint64_t> multiplexer_value;
  /// This signal is the sensor's time of validity of the message (a time counter); its SI
  /// value (s) becomes Timestamps::sensor_time_us. Must have a time unit.
  bool time_of_validity = false;
};

/// One message (DBC BO_ line) and its signals.
struct CanMessageSpec {
  std::string name;
  uint32_t id = 0;  ///< 11-bit (standard) or 29-bit (extended) identifier
  bool extended = false;
  uint8_t dlc = 8;  ///< expected data length; a frame of another length is malformed
  /// Name of the multiplexer switch signal (DBC `M`), empty when not multiplexed.
  std::string multiplexer;
  std::vector<CanSignalSpec> signals;
  /// For a message without its own time counter: the message whose time-of-validity signal
  /// dates it (e.g. dvl_velocity <- dvl_time), matched by the raw value of the signal named
  /// `time_match` that both carry (e.g. a ping sequence number). The time message must
  /// arrive first; the latest kTimeTags time messages are remembered. Empty when unused.
  std::string time_from;
  std::string time_match;
};

/// Everything that can be wrong with a table of messages, or empty when it is valid. Errors
/// name the path, e.g. "messages[2].signals[0].length: 0 is not in 1..64".
std::string validate_can_messages(const std::vector<CanMessageSpec>& messages);

/// Raw bits of one signal from a frame payload (data must hold the signal's bytes), the low
/// `length` bits of the result; no sign extension.
uint64_t can_extract_raw(const CanSignalSpec& signal, std::span<const uint8_t> data);
/// Writes the low `length` bits of `raw` into the signal's bits of `data`, other bits untouched.
void can_insert_raw(const CanSignalSpec& signal, uint64_t raw, std::span<uint8_t> data);
/// Highest byte index the signal touches + 1 (the payload length it needs).
uint32_t can_signal_end_byte(const CanSignalSpec& signal);

/// Period (µs) of a time-of-validity counter: 2^length raw steps of `scale` in its time unit,
/// for an unsigned signal with offset 0 (what a ClockMapping needs as sensor_modulus_us);
/// nullopt for other signals or a period beyond 2^62 µs.
std::optional<int64_t> can_time_signal_modulus_us(const CanSignalSpec& signal);

/// One raw step of a time signal in whole µs (e.g. 1000 for a millisecond counter), 0 when it
/// is not a time signal or the step is below 1 µs: a ClockMapping's sensor_resolution_us.
int64_t can_time_signal_resolution_us(const CanSignalSpec& signal);

/// One decoded signal value.
struct CanSignalValue {
  const CanSignalSpec* spec = nullptr;  ///< into the CanSignalDecoder's table
  uint64_t raw = 0;                     ///< raw bits as received
  std::optional<double> value_si;       ///< empty when raw is the invalid pattern or out of range
  bool out_of_range = false;            ///< physical value outside [min, max]
};

/// One decoded CAN message.
struct CanDecodedMessage {
  const CanMessageSpec* spec = nullptr;
  uint32_t id = 0;
  bool extended = false;
  /// Host receive time of the frame; sensor_time_us from the time-of-validity signal (the
  /// sensor's own clock, wrapped as the counter wraps) when the message has one and it is
  /// valid, or from the matching time message (CanMessageSpec::time_from).
  Timestamps time;
  std::optional<uint64_t> multiplexer_value;  ///< switch value for multiplexed messages
  std::vector<CanSignalValue> signals;        ///< present signals, in table order
  /// Value of the named signal in SI, empty when absent, invalid or out of range.
  std::optional<double> value(std::string_view name) const;
};

/// Decoder for a fixed table of messages. Counters (DecodeStats): every frame adds its data
/// bytes to `bytes`; unknown id -> `unsupported`; wrong length -> `malformed`; a decoded message
/// with at least one value outside [min, max] -> `out_of_range` (the message is still
/// emitted with that value empty); frames not decoded count their bytes as `dropped_bytes`.
class CanSignalDecoder {
 public:
  /// `messages` must pass validate_can_messages (throws std::invalid_argument otherwise).
  explicit CanSignalDecoder(std::vector<CanMessageSpec> messages);
  CanSignalDecoder(const CanSignalDecoder&) = delete;  // decoded messages point into the table
  CanSignalDecoder& operator=(const CanSignalDecoder&) = delete;

  /// Decodes one frame into `out` (reusing its storage); false (and counted) when the frame
  /// is not decoded.
  bool decode(uint32_t id, bool extended, std::span<const uint8_t> data, const Timestamps& time,
              CanDecodedMessage& out);
  std::optional<CanDecodedMessage> decode(uint32_t id, bool extended, std::span<const uint8_t> data,
                                          const Timestamps& time);

  const CanMessageSpec* find(uint32_t id, bool extended) const;
  const CanMessageSpec* find(std::string_view name) const;
  const std::vector<CanMessageSpec>& messages() const { return messages_; }
  const DecodeStats& stats() const { return stats_; }

 private:
  /// A remembered time message: raw value of a match signal and its sensor time.
  struct TimeTag {
    uint64_t match_raw = 0;
    int64_t sensor_time_us = 0;
    bool used = false;
  };
  static constexpr size_t kTimeTags = 4;
  using TimeTags = std::array<TimeTag, kTimeTags>;
  /// Per message index: for messages with time_from, the message index of the time source
  /// and the signals matched in both; tags kept per dependent message, newest first.
  struct TimeLink {
    size_t source = 0;
    const CanSignalSpec* match_in_source = nullptr;
    const CanSignalSpec* match_in_message = nullptr;
    TimeTags tags{};
  };
  void remember_time(const CanMessageSpec& source, std::span<const uint8_t> data,
                     int64_t sensor_time_us);
  void apply_time_link(const CanMessageSpec& message, std::span<const uint8_t> data,
                       CanDecodedMessage& out) const;

  std::vector<CanMessageSpec> messages_;
  std::vector<std::optional<TimeLink>> time_links_;  ///< by message index
  DecodeStats stats_;
};

/// A named SI value given to the encoder.
struct CanSignalInput {
  std::string_view name;
  double value_si = 0.0;
};

/// Frame payload (spec.dlc bytes) for `values` in SI; signals not given are encoded as their
/// invalid pattern when they have one, else raw 0. For multiplexed messages give the switch
/// value as an input; only signals of that multiplexer value (and unmultiplexed ones) are
/// written. Values are rounded to the nearest raw step and saturated to the raw range.
/// nullopt when a name is not a signal of the message.
std::optional<std::vector<uint8_t>> encode_can_message(const CanMessageSpec& spec,
                                                       std::span<const CanSignalInput> values);

}  // namespace nav::drivers
