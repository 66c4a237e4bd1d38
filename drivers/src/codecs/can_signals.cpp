// CAN signal codec (DBC model); bit numbering and conventions in can_signals.h.
#include "nav/drivers/codecs/can_signals.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace nav::drivers {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

struct UnitEntry {
  std::string_view name;
  CanUnitConversion conversion;
};

// Units a CAN config may use, with their SI conversion. Kept short on purpose: an unknown unit
// is a config error rather than a silently unconverted value.
constexpr UnitEntry kUnits[] = {
    {"", {1.0, 0.0, "1"}},
    {"1", {1.0, 0.0, "1"}},
    {"-", {1.0, 0.0, "1"}},
    {"count", {1.0, 0.0, "1"}},
    {"m", {1.0, 0.0, "m"}},
    {"cm", {0.01, 0.0, "m"}},
    {"mm", {0.001, 0.0, "m"}},
    {"m/s", {1.0, 0.0, "m/s"}},
    {"cm/s", {0.01, 0.0, "m/s"}},
    {"mm/s", {0.001, 0.0, "m/s"}},
    {"m/s^2", {1.0, 0.0, "m/s^2"}},
    {"rad", {1.0, 0.0, "rad"}},
    {"mrad", {0.001, 0.0, "rad"}},
    {"deg", {kDegToRad, 0.0, "rad"}},
    {"rad/s", {1.0, 0.0, "rad/s"}},
    {"deg/s", {kDegToRad, 0.0, "rad/s"}},
    {"deg/h", {kDegToRad / 3600.0, 0.0, "rad/s"}},
    {"s", {1.0, 0.0, "s"}},
    {"ms", {1e-3, 0.0, "s"}},
    {"us", {1e-6, 0.0, "s"}},
    {"Pa", {1.0, 0.0, "Pa"}},
    {"kPa", {1e3, 0.0, "Pa"}},
    {"bar", {1e5, 0.0, "Pa"}},
    {"dbar", {1e4, 0.0, "Pa"}},
    {"degC", {1.0, 0.0, "degC"}},
    {"K", {1.0, -273.15, "degC"}},
    {"V", {1.0, 0.0, "V"}},
};

uint64_t low_mask(uint32_t length) {
  return length >= 64 ? ~uint64_t{0} : (uint64_t{1} << length) - 1;
}

/// Bit position of the Motorola start bit in MSB-first ("msb0") numbering, where position q
/// is bit 7 - q % 8 of byte q / 8 and successive signal bits have successive positions.
uint32_t motorola_msb0(uint32_t start_bit) { return 8 * (start_bit / 8) + (7 - start_bit % 8); }

int64_t sign_extend(uint64_t raw, uint32_t length) {
  if (length >= 64) return static_cast<int64_t>(raw);
  const uint64_t sign = uint64_t{1} << (length - 1);
  return static_cast<int64_t>((raw ^ sign) - sign);
}

double raw_to_physical(const CanSignalSpec& s, uint64_t raw) {
  const double r =
      s.is_signed ? static_cast<double>(sign_extend(raw, s.length)) : static_cast<double>(raw);
  return r * s.scale + s.offset;
}

/// Raw bits for a physical value: rounded, saturated to the raw range of the signal.
uint64_t physical_to_raw(const CanSignalSpec& s, double physical) {
  const double r = std::nearbyint((physical - s.offset) / s.scale);
  if (s.is_signed) {
    const int64_t hi =
        s.length >= 64 ? std::numeric_limits<int64_t>::max() : (int64_t{1} << (s.length - 1)) - 1;
    const int64_t lo = -hi - 1;
    int64_t v = 0;
    if (!(r > static_cast<double>(lo))) {
      v = lo;
    } else if (!(r < static_cast<double>(hi))) {
      v = hi;
    } else {
      v = static_cast<int64_t>(r);
    }
    return static_cast<uint64_t>(v) & low_mask(s.length);
  }
  const uint64_t hi = low_mask(s.length);
  if (!(r > 0.0)) return 0;
  if (!(r < static_cast<double>(hi))) return hi;
  return static_cast<uint64_t>(r);
}

std::string signal_path(size_t m, size_t s) {
  return "messages[" + std::to_string(m) + "].signals[" + std::to_string(s) + "]";
}

/// First problem of one signal of message `m` (its index `si`), or empty.
std::string validate_signal(const CanMessageSpec& msg, size_t m, size_t si) {
  const CanSignalSpec& s = msg.signals[si];
  const std::string path = signal_path(m, si);
  std::ostringstream e;
  if (s.name.empty()) {
    e << path << ".name: must not be empty";
  } else if (s.length < 1 || s.length > 64) {
    e << path << ".length: " << s.length << " is not in 1..64";
  } else if (s.start_bit > 63) {
    e << path << ".start_bit: " << s.start_bit << " is not in 0..63";
  } else if (s.byte_order == CanByteOrder::kIntel && s.start_bit + s.length > 64) {
    e << path << ": bits " << s.start_bit << ".." << s.start_bit + s.length - 1
      << " run past bit 63 (Intel)";
  } else if (s.byte_order == CanByteOrder::kMotorola &&
             motorola_msb0(s.start_bit) + s.length > 64) {
    e << path << ": " << s.length << " bits from Motorola start bit " << s.start_bit
      << " run past the end of an 8-byte frame";
  } else if (can_signal_end_byte(s) > msg.dlc) {
    e << path << ": needs " << can_signal_end_byte(s) << " data bytes but the message dlc is "
      << int{msg.dlc};
  } else if (!std::isfinite(s.scale) || s.scale == 0.0) {
    e << path << ".scale: " << s.scale << " must be finite and non-zero";
  } else if (!std::isfinite(s.offset)) {
    e << path << ".offset: must be finite";
  } else if (s.min && s.max && !(*s.min <= *s.max)) {
    e << path << ".min: " << *s.min << " is greater than max " << *s.max;
  } else if (!can_unit_to_si(s.unit)) {
    e << path << ".unit: unknown unit \"" << s.unit << "\"";
  } else if (s.invalid_raw && (*s.invalid_raw & ~low_mask(s.length)) != 0) {
    e << path << ".invalid: " << *s.invalid_raw << " does not fit in " << s.length << " bits";
  } else if (s.multiplexer_value && msg.multiplexer.empty()) {
    e << path << ".multiplexer_value: message \"" << msg.name << "\" has no multiplexer";
  } else if (s.multiplexer_value && s.name == msg.multiplexer) {
    e << path << ".multiplexer_value: the multiplexer switch cannot itself be multiplexed";
  } else if (s.time_of_validity && can_unit_to_si(s.unit)->si_unit != "s") {
    e << path << ".time_of_validity: unit \"" << s.unit << "\" is not a time unit";
  }
  return e.str();
}

std::string validate_message(const CanMessageSpec& msg, size_t m) {
  const std::string path = "messages[" + std::to_string(m) + "]";
  std::ostringstream e;
  const uint32_t id_max = msg.extended ? 0x1FFFFFFFu : 0x7FFu;
  if (msg.name.empty()) {
    e << path << ".name: must not be empty";
  } else if (msg.id > id_max) {
    e << path << ".id: 0x" << std::hex << msg.id << " does not fit in "
      << (msg.extended ? "29" : "11") << " bits" << (msg.extended ? "" : " (set extended: true?)");
  } else if (msg.dlc > 8) {
    e << path << ".dlc: " << int{msg.dlc} << " is not in 0..8";
  } else if (msg.signals.empty()) {
    e << path << ".signals: a message needs at least one signal";
  }
  if (!e.str().empty()) return e.str();
  std::set<std::string> names;
  size_t time_signals = 0;
  for (size_t si = 0; si < msg.signals.size(); ++si) {
    if (std::string err = validate_signal(msg, m, si); !err.empty()) return err;
    if (!names.insert(msg.signals[si].name).second) {
      return signal_path(m, si) + ".name: \"" + msg.signals[si].name +
             "\" is used twice in message \"" + msg.name + "\"";
    }
    if (msg.signals[si].time_of_validity && ++time_signals > 1) {
      return signal_path(m, si) + ".time_of_validity: a message has at most one time signal";
    }
  }
  if (!msg.multiplexer.empty()) {
    for (const CanSignalSpec& s : msg.signals) {
      if (s.name == msg.multiplexer) return {};
    }
    return path + ".multiplexer: \"" + msg.multiplexer + "\" is not a signal of the message";
  }
  return {};
}

const CanSignalSpec* find_signal(const CanMessageSpec& msg, std::string_view name) {
  for (const CanSignalSpec& s : msg.signals) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

bool has_time_signal(const CanMessageSpec& msg) {
  for (const CanSignalSpec& s : msg.signals) {
    if (s.time_of_validity) return true;
  }
  return false;
}

/// The time_from / time_match pair of message `m`, or empty.
std::string validate_time_link(const std::vector<CanMessageSpec>& messages, size_t m) {
  const CanMessageSpec& msg = messages[m];
  const std::string path = "messages[" + std::to_string(m) + "]";
  if (msg.time_from.empty() && msg.time_match.empty()) return {};
  if (msg.time_from.empty() || msg.time_match.empty()) {
    return path + (msg.time_from.empty() ? ".time_from" : ".time_match") +
           ": time_from and time_match go together";
  }
  if (has_time_signal(msg)) {
    return path + ".time_from: the message has its own time_of_validity signal";
  }
  const CanMessageSpec* source = nullptr;
  for (const CanMessageSpec& other : messages) {
    if (other.name == msg.time_from) source = &other;
  }
  if (source == nullptr || source == &msg) {
    return path + ".time_from: \"" + msg.time_from + "\" is not another message of the table";
  }
  if (!has_time_signal(*source)) {
    return path + ".time_from: message \"" + msg.time_from + "\" has no time_of_validity signal";
  }
  for (const CanMessageSpec* side : {&msg, source}) {
    const CanSignalSpec* match = find_signal(*side, msg.time_match);
    if (match == nullptr || match->multiplexer_value) {
      return path + ".time_match: \"" + msg.time_match +
             "\" is not an unmultiplexed signal of message \"" + side->name + "\"";
    }
  }
  return {};
}

}  // namespace

std::optional<CanUnitConversion> can_unit_to_si(std::string_view unit) {
  for (const UnitEntry& u : kUnits) {
    if (u.name == unit) return u.conversion;
  }
  return std::nullopt;
}

std::string validate_can_messages(const std::vector<CanMessageSpec>& messages) {
  std::set<std::string> names;
  std::set<std::pair<uint32_t, bool>> ids;
  for (size_t m = 0; m < messages.size(); ++m) {
    const CanMessageSpec& msg = messages[m];
    if (std::string err = validate_message(msg, m); !err.empty()) return err;
    const std::string path = "messages[" + std::to_string(m) + "]";
    if (!names.insert(msg.name).second) {
      return path + ".name: \"" + msg.name + "\" is used by an earlier message";
    }
    if (!ids.insert({msg.id, msg.extended}).second) {
      std::ostringstream e;
      e << path << ".id: 0x" << std::hex << msg.id << " is used by an earlier message";
      return e.str();
    }
  }
  for (size_t m = 0; m < messages.size(); ++m) {
    if (std::string err = validate_time_link(messages, m); !err.empty()) return err;
  }
  return {};
}

std::optional<int64_t> can_time_signal_modulus_us(const CanSignalSpec& s) {
  const std::optional<CanUnitConversion> unit = can_unit_to_si(s.unit);
  if (!unit || unit->si_unit != "s" || s.is_signed || s.offset != 0.0 || s.scale <= 0.0) {
    return std::nullopt;
  }
  const double period_us = std::ldexp(s.scale * unit->factor * 1e6, static_cast<int>(s.length));
  if (!(period_us >= 1.0 && period_us < std::ldexp(1.0, 62))) return std::nullopt;
  return std::llround(period_us);
}

int64_t can_time_signal_resolution_us(const CanSignalSpec& s) {
  const std::optional<CanUnitConversion> unit = can_unit_to_si(s.unit);
  if (!unit || unit->si_unit != "s") return 0;
  const double step_us = std::abs(s.scale) * unit->factor * 1e6;
  return step_us >= 1.0 && step_us < 1e12 ? std::llround(step_us) : 0;
}

uint32_t can_signal_end_byte(const CanSignalSpec& s) {
  const uint32_t last = s.byte_order == CanByteOrder::kIntel
                            ? s.start_bit + s.length - 1
                            : motorola_msb0(s.start_bit) + s.length - 1;
  return last / 8 + 1;
}

uint64_t can_extract_raw(const CanSignalSpec& s, std::span<const uint8_t> data) {
  uint64_t raw = 0;
  if (s.byte_order == CanByteOrder::kIntel) {
    for (uint32_t i = 0; i < s.length; ++i) {
      const uint32_t p = s.start_bit + i;
      if (p / 8 >= data.size()) break;
      raw |= static_cast<uint64_t>((data[p / 8] >> (p % 8)) & 1u) << i;
    }
    return raw;
  }
  const uint32_t msb0 = motorola_msb0(s.start_bit);
  for (uint32_t i = 0; i < s.length; ++i) {
    const uint32_t q = msb0 + i;  // i-th bit from the most significant one
    const uint64_t bit = q / 8 < data.size() ? (data[q / 8] >> (7 - q % 8)) & 1u : 0u;
    raw = (raw << 1) | bit;
  }
  return raw;
}

void can_insert_raw(const CanSignalSpec& s, uint64_t raw, std::span<uint8_t> data) {
  for (uint32_t i = 0; i < s.length; ++i) {
    uint32_t byte = 0;
    uint32_t bit = 0;
    uint64_t value_bit = 0;
    if (s.byte_order == CanByteOrder::kIntel) {
      const uint32_t p = s.start_bit + i;
      byte = p / 8;
      bit = p % 8;
      value_bit = (raw >> i) & 1u;
    } else {
      const uint32_t q = motorola_msb0(s.start_bit) + i;
      byte = q / 8;
      bit = 7 - q % 8;
      value_bit = (raw >> (s.length - 1 - i)) & 1u;
    }
    if (byte >= data.size()) continue;
    data[byte] = static_cast<uint8_t>((data[byte] & ~(1u << bit)) | (value_bit << bit));
  }
}

std::optional<double> CanDecodedMessage::value(std::string_view name) const {
  for (const CanSignalValue& v : signals) {
    if (v.spec->name == name) return v.value_si;
  }
  return std::nullopt;
}

CanSignalDecoder::CanSignalDecoder(std::vector<CanMessageSpec> messages)
    : messages_(std::move(messages)) {
  if (std::string err = validate_can_messages(messages_); !err.empty()) {
    throw std::invalid_argument("CAN message table: " + err);
  }
  time_links_.resize(messages_.size());
  for (size_t m = 0; m < messages_.size(); ++m) {
    const CanMessageSpec& msg = messages_[m];
    if (msg.time_from.empty()) continue;
    const CanMessageSpec* source = find(msg.time_from);
    time_links_[m] = TimeLink{static_cast<size_t>(source - messages_.data()),
                              find_signal(*source, msg.time_match),
                              find_signal(msg, msg.time_match),
                              {}};
  }
}

void CanSignalDecoder::remember_time(const CanMessageSpec& source, std::span<const uint8_t> data,
                                     int64_t sensor_time_us) {
  const auto source_index = static_cast<size_t>(&source - messages_.data());
  for (std::optional<TimeLink>& link : time_links_) {
    if (!link || link->source != source_index) continue;
    std::copy_backward(link->tags.begin(), link->tags.end() - 1, link->tags.end());
    link->tags[0] = TimeTag{can_extract_raw(*link->match_in_source, data), sensor_time_us, true};
  }
}

void CanSignalDecoder::apply_time_link(const CanMessageSpec& message, std::span<const uint8_t> data,
                                       CanDecodedMessage& out) const {
  const std::optional<TimeLink>& link =
      time_links_[static_cast<size_t>(&message - messages_.data())];
  if (!link) return;
  const uint64_t raw = can_extract_raw(*link->match_in_message, data);
  for (const TimeTag& tag : link->tags) {  // newest first
    if (tag.used && tag.match_raw == raw) {
      out.time.sensor_time_us = tag.sensor_time_us;
      return;
    }
  }
}

const CanMessageSpec* CanSignalDecoder::find(uint32_t id, bool extended) const {
  for (const CanMessageSpec& m : messages_) {
    if (m.id == id && m.extended == extended) return &m;
  }
  return nullptr;
}

const CanMessageSpec* CanSignalDecoder::find(std::string_view name) const {
  for (const CanMessageSpec& m : messages_) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

bool CanSignalDecoder::decode(uint32_t id, bool extended, std::span<const uint8_t> data,
                              const Timestamps& time, CanDecodedMessage& out) {
  stats_.bytes += data.size();
  const CanMessageSpec* spec = find(id, extended);
  if (spec == nullptr) {
    ++stats_.unsupported;
    stats_.dropped_bytes += data.size();
    return false;
  }
  if (data.size() != spec->dlc) {
    ++stats_.malformed;
    stats_.dropped_bytes += data.size();
    return false;
  }
  out.spec = spec;
  out.id = id;
  out.extended = extended;
  out.time = Timestamps{time.host, std::nullopt};
  out.multiplexer_value.reset();
  out.signals.clear();
  if (!spec->multiplexer.empty()) {
    out.multiplexer_value = can_extract_raw(*find_signal(*spec, spec->multiplexer), data);
  }
  bool any_out_of_range = false;
  for (const CanSignalSpec& s : spec->signals) {
    if (s.multiplexer_value && s.multiplexer_value != out.multiplexer_value) continue;
    CanSignalValue v{&s, can_extract_raw(s, data), std::nullopt, false};
    if (!(s.invalid_raw && *s.invalid_raw == v.raw)) {
      const double physical = raw_to_physical(s, v.raw);
      v.out_of_range = (s.min && physical < *s.min) || (s.max && physical > *s.max);
      if (!v.out_of_range) {
        const CanUnitConversion unit = *can_unit_to_si(s.unit);
        v.value_si = physical * unit.factor + unit.offset;
      }
    }
    any_out_of_range = any_out_of_range || v.out_of_range;
    if (s.time_of_validity && v.value_si && std::abs(*v.value_si) < 9e12) {
      out.time.sensor_time_us = std::llround(*v.value_si * 1e6);
    }
    out.signals.push_back(v);
  }
  if (out.time.sensor_time_us) {
    remember_time(*spec, data, *out.time.sensor_time_us);
  } else {
    apply_time_link(*spec, data, out);
  }
  if (any_out_of_range) ++stats_.out_of_range;
  ++stats_.records;
  return true;
}

std::optional<CanDecodedMessage> CanSignalDecoder::decode(uint32_t id, bool extended,
                                                          std::span<const uint8_t> data,
                                                          const Timestamps& time) {
  CanDecodedMessage out;
  if (!decode(id, extended, data, time, out)) return std::nullopt;
  return out;
}

std::optional<std::vector<uint8_t>> encode_can_message(const CanMessageSpec& spec,
                                                       std::span<const CanSignalInput> values) {
  for (const CanSignalInput& in : values) {
    if (find_signal(spec, in.name) == nullptr) return std::nullopt;
  }
  auto given = [&](std::string_view name) -> const CanSignalInput* {
    for (const CanSignalInput& in : values) {
      if (in.name == name) return &in;
    }
    return nullptr;
  };
  std::vector<uint8_t> data(spec.dlc, 0);
  std::optional<uint64_t> mux;
  if (const CanSignalSpec* sw = find_signal(spec, spec.multiplexer)) {
    const CanSignalInput* in = given(sw->name);
    mux = in ? physical_to_raw(*sw, in->value_si) : 0;  // the switch is dimensionless
  }
  for (const CanSignalSpec& s : spec.signals) {
    if (s.multiplexer_value && s.multiplexer_value != mux) continue;
    const CanSignalInput* in = given(s.name);
    const CanUnitConversion unit = can_unit_to_si(s.unit).value_or(CanUnitConversion{});
    uint64_t raw = 0;
    if (in != nullptr && std::isfinite(in->value_si)) {
      raw = physical_to_raw(s, (in->value_si - unit.offset) / unit.factor);
    } else if (s.invalid_raw) {
      raw = *s.invalid_raw;
    }
    can_insert_raw(s, raw, data);
  }
  return data;
}

}  // namespace nav::drivers
