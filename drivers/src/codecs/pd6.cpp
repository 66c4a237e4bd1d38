// PD6 ASCII decoder and encoder ("WorkHorse Commands and Output Data Format", Special Output
// Data Formats, PD6 Output Format; field layout summarised in pd6.h).
#include "nav/drivers/codecs/pd6.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string_view>

#include "pd0_wire.h"

namespace nav::drivers {
namespace {

using pd0_wire::CivilTime;

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kInvalid = -32768.0;
constexpr double kMaxVelocityMps = 20.0;
constexpr double kMaxRangeM = 2000.0;
constexpr double kMaxDistanceM = 99999999.99;  // widest the ±EEEEEEEE.EE field can hold

/// Splits on ',' (no quoting in PD6).
std::vector<std::string_view> split(std::string_view s) {
  std::vector<std::string_view> fields;
  std::size_t begin = 0;
  for (;;) {
    const std::size_t comma = s.find(',', begin);
    fields.push_back(s.substr(begin, comma == std::string_view::npos ? comma : comma - begin));
    if (comma == std::string_view::npos) return fields;
    begin = comma + 1;
  }
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
  while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
  return s;
}

/// Number with optional sign and spaces ("  +12.50", "-32768"); empty when not a number.
std::optional<double> number(std::string_view field) {
  std::string_view s = trim(field);
  bool negative = false;
  if (!s.empty() && (s.front() == '+' || s.front() == '-')) {
    negative = s.front() == '-';
    s.remove_prefix(1);
    s = trim(s);  // the manual's padded fields may put spaces after the sign
  }
  if (s.empty() || !(s.front() >= '0' && s.front() <= '9')) return std::nullopt;
  double value = 0.0;
  const auto [end, ec] =
      std::from_chars(s.data(), s.data() + s.size(), value, std::chars_format::fixed);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(value)) {
    return std::nullopt;
  }
  return negative ? -value : value;
}

/// Range check on a parsed value: outside [lo, hi] -> empty and counted.
std::optional<double> ranged(double value, double lo, double hi, int& rejected) {
  if (value >= lo && value <= hi) return value;
  ++rejected;
  return std::nullopt;
}

bool parse_attitude(const std::vector<std::string_view>& f, Pd6Attitude& a, int& rejected) {
  if (f.size() != 4) return false;
  const auto pitch = number(f[1]), roll = number(f[2]), heading = number(f[3]);
  if (!pitch || !roll || !heading) return false;
  a.pitch_rad = ranged(*pitch, -90.0, 90.0, rejected);
  a.roll_rad = ranged(*roll, -90.0, 90.0, rejected);
  a.heading_rad = ranged(*heading, 0.0, 360.0, rejected);
  if (a.heading_rad && *a.heading_rad == 360.0) a.heading_rad = 0.0;
  for (auto* angle : {&a.pitch_rad, &a.roll_rad, &a.heading_rad}) {
    if (*angle) **angle *= kDegToRad;
  }
  return true;
}

std::optional<int64_t> ts_time(std::string_view field, int& rejected) {
  const std::string_view s = trim(field);
  if (s.size() != 14) return std::nullopt;
  int v[7];
  for (int i = 0; i < 7; ++i) {
    const char a = s[2 * i], b = s[2 * i + 1];
    if (a < '0' || a > '9' || b < '0' || b > '9') return std::nullopt;
    v[i] = (a - '0') * 10 + (b - '0');
  }
  const int year = v[0] >= 80 ? 1900 + v[0] : 2000 + v[0];
  auto t = pd0_wire::civil_to_unix_us({year, v[1], v[2], v[3], v[4], v[5], v[6]});
  if (!t) ++rejected;
  return t;
}

bool parse_timing(const std::vector<std::string_view>& f, Pd6TimingScaling& t,
                  std::optional<int64_t>& time_us, int& rejected) {
  if (f.size() != 7) return false;
  const std::string_view stamp = trim(f[1]);
  if (stamp.size() != 14) return false;
  for (char c : stamp) {
    if (c < '0' || c > '9') return false;
  }
  const auto salinity = number(f[2]), temperature = number(f[3]), depth = number(f[4]),
             sound = number(f[5]);
  const std::string_view bit = trim(f[6]);
  unsigned bit_value = 0;
  const auto [end, ec] = std::from_chars(bit.data(), bit.data() + bit.size(), bit_value, 16);
  if (!salinity || !temperature || !depth || !sound || bit.empty() || ec != std::errc() ||
      end != bit.data() + bit.size() || bit_value > 0xFFFF) {
    return false;
  }
  time_us = ts_time(stamp, rejected);
  t.salinity_ppt = ranged(*salinity, 0.0, 40.0, rejected);
  t.temperature_c = ranged(*temperature, -10.0, 50.0, rejected);
  t.depth_m = ranged(*depth, 0.0, 11000.0, rejected);
  t.sound_speed_mps = ranged(*sound, 1400.0, 1600.0, rejected);
  t.bit_result = uint16_t(bit_value);
  return true;
}

bool parse_velocity(const std::vector<std::string_view>& f, Pd6Velocity& v, int& rejected) {
  const std::size_t components = v.frame == Pd6Frame::kInstrument ? 4 : 3;
  if (f.size() != components + 2) return false;
  const std::string_view status = trim(f.back());
  if (status != "A" && status != "V") return false;
  v.valid = status == "A";
  for (std::size_t i = 0; i < components; ++i) {
    const auto mmps = number(f[1 + i]);
    if (!mmps) return false;
    if (!v.valid || *mmps == kInvalid) continue;
    v.velocity_mps[i] = ranged(*mmps * 0.001, -kMaxVelocityMps, kMaxVelocityMps, rejected);
  }
  return true;
}

bool parse_distance(const std::vector<std::string_view>& f, Pd6Distance& d, int& rejected) {
  if (f.size() != 6) return false;
  std::optional<double> values[5];
  for (int i = 0; i < 5; ++i) {
    values[i] = number(f[1 + i]);
    if (!values[i]) return false;
    if (*values[i] == kInvalid) values[i].reset();
  }
  for (int i = 0; i < 3; ++i) {
    if (values[i])
      d.distance_enu_m[i] = ranged(*values[i], -kMaxDistanceM, kMaxDistanceM, rejected);
  }
  if (values[3]) d.range_m = ranged(*values[3], 0.0, kMaxRangeM, rejected);
  if (values[4]) d.time_since_valid_s = ranged(*values[4], 0.0, 1e6, rejected);
  return true;
}

std::optional<Pd6Reference> reference_of(char c) {
  if (c == 'W') return Pd6Reference::kWaterMass;
  if (c == 'B') return Pd6Reference::kBottom;
  return std::nullopt;
}

char reference_letter(Pd6Reference r) { return r == Pd6Reference::kBottom ? 'B' : 'W'; }

char frame_letter(Pd6Frame f) {
  return f == Pd6Frame::kInstrument ? 'I' : f == Pd6Frame::kShip ? 'S' : 'E';
}

}  // namespace

std::string pd6_line_name(const Pd6Record& record) {
  if (std::holds_alternative<Pd6Attitude>(record.value)) return "SA";
  if (std::holds_alternative<Pd6TimingScaling>(record.value)) return "TS";
  if (const auto* v = std::get_if<Pd6Velocity>(&record.value)) {
    return {reference_letter(v->reference), frame_letter(v->frame)};
  }
  return {reference_letter(std::get<Pd6Distance>(record.value).reference), 'D'};
}

std::optional<Pd6Record> parse_pd6_line(std::string_view line, bool& unsupported,
                                        int& out_of_range_fields) {
  unsupported = false;
  out_of_range_fields = 0;
  if (line.size() < 4 || line[0] != ':' || line[3] != ',') return std::nullopt;
  for (char c : line) {
    if (c < 0x20 || c > 0x7E) return std::nullopt;  // printable ASCII only
  }
  const std::vector<std::string_view> fields = split(line);
  const char a = line[1], b = line[2];
  Pd6Record record;
  bool ok = false;
  if (a == 'S' && b == 'A') {
    Pd6Attitude v;
    ok = parse_attitude(fields, v, out_of_range_fields);
    record.value = v;
  } else if (a == 'T' && b == 'S') {
    Pd6TimingScaling v;
    ok = parse_timing(fields, v, record.time.sensor_time_us, out_of_range_fields);
    record.value = v;
  } else if (const auto reference = reference_of(a); reference && b == 'D') {
    Pd6Distance v;
    v.reference = *reference;
    ok = parse_distance(fields, v, out_of_range_fields);
    record.value = v;
  } else if (reference && (b == 'I' || b == 'S' || b == 'E')) {
    Pd6Velocity v;
    v.reference = *reference;
    v.frame = b == 'I' ? Pd6Frame::kInstrument : b == 'S' ? Pd6Frame::kShip : Pd6Frame::kEarth;
    ok = parse_velocity(fields, v, out_of_range_fields);
    record.value = v;
  } else {
    const bool id_ok = (a >= 'A' && a <= 'Z') && (b >= 'A' && b <= 'Z');
    unsupported = id_ok;
    return std::nullopt;
  }
  if (!ok) return std::nullopt;
  return record;
}

void Pd6Decoder::drop_line() {
  stats_.dropped_bytes += line_.size();
  line_.clear();
}

void Pd6Decoder::end_line(const HostTime& received, std::vector<Pd6Record>& out) {
  std::string_view text = line_;
  text.remove_suffix(1);  // LF
  if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
  bool unsupported = false;
  int rejected = 0;
  auto record = parse_pd6_line(text, unsupported, rejected);
  if (!record) {
    ++(unsupported ? stats_.unsupported : stats_.malformed);
    drop_line();
    return;
  }
  if (std::holds_alternative<Pd6Attitude>(record->value)) {
    ensemble_time_us_.reset();  // :SA opens the next ensemble
  } else if (std::holds_alternative<Pd6TimingScaling>(record->value)) {
    ensemble_time_us_ = record->time.sensor_time_us;
  } else {
    record->time.sensor_time_us = ensemble_time_us_;
  }
  if (rejected > 0) ++stats_.out_of_range;
  record->time.host = received;
  out.push_back(std::move(*record));
  ++stats_.records;
  line_.clear();
}

void Pd6Decoder::feed(std::span<const uint8_t> bytes, const HostTime& received,
                      std::vector<Pd6Record>& out) {
  stats_.bytes += bytes.size();
  for (const uint8_t byte : bytes) {
    const char c = char(byte);
    if (discarding_) {  // rest of an over-long line, up to its LF
      ++stats_.dropped_bytes;
      if (c == '\n') discarding_ = false;
      continue;
    }
    if (c == ':' && !line_.empty()) {  // a new line starts before the last one ended
      ++stats_.malformed;
      drop_line();
    }
    if (line_.empty() && c != ':') {
      ++stats_.dropped_bytes;  // between lines
      continue;
    }
    line_.push_back(c);
    if (c == '\n') {
      end_line(received, out);
    } else if (line_.size() >= kMaxLineBytes) {
      ++stats_.malformed;
      drop_line();
      discarding_ = true;
    }
  }
}

std::string encode_pd6(const Pd6Record& record) {
  char buf[160];
  const auto or_out = [](const std::optional<double>& v, double out_of_range) {
    return v ? *v : out_of_range;
  };
  if (const auto* a = std::get_if<Pd6Attitude>(&record.value)) {
    const double r2d = 180.0 / std::numbers::pi;
    double heading_deg = 999.99;  // out of range: decodes empty
    if (a->heading_rad) {         // wrapped to [0, 360) after rounding to the field's 0.01 deg
      heading_deg =
          std::round(std::fmod(std::fmod(*a->heading_rad * r2d, 360.0) + 360.0, 360.0) * 100.0) /
          100.0;
      if (heading_deg >= 360.0) heading_deg = 0.0;
    }
    std::snprintf(buf, sizeof buf, ":SA,%+06.2f,%+06.2f,%06.2f\r\n",
                  a->pitch_rad ? *a->pitch_rad * r2d : 99.99,
                  a->roll_rad ? *a->roll_rad * r2d : 99.99, heading_deg);
  } else if (const auto* t = std::get_if<Pd6TimingScaling>(&record.value)) {
    char stamp[16] = "00000000000000";  // month 0: decodes as "no time"
    if (record.time.sensor_time_us) {
      const CivilTime c = pd0_wire::unix_us_to_civil(*record.time.sensor_time_us);
      std::snprintf(stamp, sizeof stamp, "%02d%02d%02d%02d%02d%02d%02d", c.year % 100, c.month,
                    c.day, c.hour, c.minute, c.second, c.hundredths);
    }
    std::snprintf(buf, sizeof buf, ":TS,%s,%04.1f,%+05.1f,%06.1f,%06.1f,%3X\r\n", stamp,
                  or_out(t->salinity_ppt, 99.9), or_out(t->temperature_c, 99.9),
                  or_out(t->depth_m, 99999.9), or_out(t->sound_speed_mps, 0.0),
                  unsigned(t->bit_result));
  } else if (const auto* v = std::get_if<Pd6Velocity>(&record.value)) {
    const int components = v->frame == Pd6Frame::kInstrument ? 4 : 3;
    int n = std::snprintf(buf, sizeof buf, ":%c%c", reference_letter(v->reference),
                          frame_letter(v->frame));
    bool valid = v->valid;
    for (int i = 0; i < components; ++i) {
      const double mmps = v->velocity_mps[i] ? std::round(*v->velocity_mps[i] * 1000.0) : kInvalid;
      n += std::snprintf(buf + n, sizeof buf - std::size_t(n), ",%+06.0f",
                         std::fmax(-32768.0, std::fmin(32767.0, mmps)));
    }
    std::snprintf(buf + n, sizeof buf - std::size_t(n), ",%c\r\n", valid ? 'A' : 'V');
  } else {
    const auto& d = std::get<Pd6Distance>(record.value);
    const auto f = [](const std::optional<double>& x) { return x ? *x : kInvalid; };
    std::snprintf(buf, sizeof buf, ":%cD,%+012.2f,%+012.2f,%+012.2f,%07.2f,%06.2f\r\n",
                  reference_letter(d.reference), f(d.distance_enu_m[0]), f(d.distance_enu_m[1]),
                  f(d.distance_enu_m[2]), f(d.range_m), f(d.time_since_valid_s));
  }
  return buf;
}

}  // namespace nav::drivers
