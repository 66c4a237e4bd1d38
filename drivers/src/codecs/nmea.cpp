// NMEA 0183 heading/attitude decoder and encoder (HDT, iXblue PHTRO and PIXSE). Sentence
// layouts: NMEA 0183 v4.10 (HDT), iXblue "Octans/PHINS standard" and "PHINS standard"
// protocols as documented in the iXblue interface library; see nmea.h for the conventions.
#include "nav/drivers/codecs/nmea.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "ascii_text.h"

namespace nav::drivers {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr std::size_t kMaxLimitChars = 4096;

double wrap_pi(double angle_rad) {
  double wrapped = std::remainder(angle_rad, 2.0 * std::numbers::pi);
  if (wrapped <= -std::numbers::pi) wrapped += 2.0 * std::numbers::pi;
  return wrapped;
}

/// Heading in [0, 360) degrees for the wire.
double heading_deg_0_360(double heading_rad) {
  double deg = wrap_pi(heading_rad) * kRadToDeg;
  if (deg < 0.0) deg += 360.0;
  return deg;
}

enum class Outcome { kRecord, kMalformed, kOutOfRange, kUnsupported };

struct Parsed {
  Outcome outcome = Outcome::kMalformed;
  NmeaRecord record;
};

Parsed fail(Outcome outcome) { return Parsed{outcome, NmeaHeading{}}; }
template <typename R>
Parsed ok(R record) {
  return Parsed{Outcome::kRecord, NmeaRecord{std::move(record)}};
}

/// Reads `count` decimals from fields[first..]; false when any is absent or not a number.
template <std::size_t N>
bool numbers(const ascii::Fields& f, std::size_t first, std::array<double, N>& v) {
  for (std::size_t i = 0; i < N; ++i) {
    const auto value = ascii::parse_decimal(f[first + i]);
    if (!value) return false;
    v[i] = *value;
  }
  return true;
}

using ascii::in_range;

Parsed parse_hdt(const ascii::Fields& f, std::string_view address) {
  // NMEA 0183 HDT: heading degrees true, 'T'.
  if (f.count < 2 || f.count > 3) return fail(Outcome::kMalformed);
  if (f.count == 3 && f[2] != "T" && !f[2].empty()) return fail(Outcome::kMalformed);
  const auto heading = ascii::parse_decimal(f[1]);
  if (!heading) return fail(Outcome::kMalformed);
  if (!in_range(*heading, 0.0, 360.0)) return fail(Outcome::kOutOfRange);
  NmeaHeading r;
  r.sentence = NmeaSentence::kHdt;
  r.talker = {address[0], address[1]};
  r.heading_rad = wrap_pi(*heading * kDegToRad);
  return ok(r);
}

Parsed parse_phtro(const ascii::Fields& f) {
  // $PHTRO,x.xx,a,y.yy,b: pitch magnitude, 'M' bow up / 'P' bow down; roll magnitude,
  // 'B' port down / 'T' port up.
  if (f.count != 5) return fail(Outcome::kMalformed);
  std::array<double, 1> pitch{}, roll{};
  if (!numbers(f, 1, pitch) || !numbers(f, 3, roll)) return fail(Outcome::kMalformed);
  if (pitch[0] < 0.0 || roll[0] < 0.0) return fail(Outcome::kMalformed);
  double pitch_sign = 0.0, roll_sign = 0.0;
  if (f[2] == "M") pitch_sign = 1.0;
  if (f[2] == "P") pitch_sign = -1.0;
  if (f[4] == "T") roll_sign = 1.0;
  if (f[4] == "B") roll_sign = -1.0;
  if (pitch_sign == 0.0 || roll_sign == 0.0) return fail(Outcome::kMalformed);
  if (pitch[0] > 90.0 || roll[0] > 180.0) return fail(Outcome::kOutOfRange);
  NmeaAttitude r;
  r.sentence = NmeaSentence::kPhtro;
  r.pitch_rad = pitch_sign * pitch[0] * kDegToRad;
  r.roll_rad = wrap_pi(roll_sign * roll[0] * kDegToRad);
  return ok(r);
}

Parsed parse_pixse(const ascii::Fields& f, const NmeaOptions& options) {
  const std::string_view type = f[1];
  if (type == "ATITUD") {
    std::array<double, 2> v{};
    if (f.count != 4 || !numbers(f, 2, v)) return fail(Outcome::kMalformed);
    if (!in_range(v[0], -180.0, 180.0) || !in_range(v[1], -90.0, 90.0)) {
      return fail(Outcome::kOutOfRange);
    }
    NmeaAttitude r;
    r.sentence = NmeaSentence::kIxseAtitud;
    r.roll_rad = wrap_pi(v[0] * kDegToRad);
    r.pitch_rad = (options.ixblue_pitch_positive_bow_down ? -v[1] : v[1]) * kDegToRad;
    return ok(r);
  }
  if (type == "HEADNG") {
    std::array<double, 1> v{};
    if (f.count != 3 || !numbers(f, 2, v)) return fail(Outcome::kMalformed);
    if (!in_range(v[0], 0.0, 360.0)) return fail(Outcome::kOutOfRange);
    NmeaHeading r;
    r.sentence = NmeaSentence::kIxseHeadng;
    r.talker = {'I', 'X'};
    r.heading_rad = wrap_pi(v[0] * kDegToRad);
    return ok(r);
  }
  if (type == "POSITI") {
    std::array<double, 2> v{};
    if (f.count != 5 || !numbers(f, 2, v)) return fail(Outcome::kMalformed);
    NmeaPosition r;
    if (!f[4].empty()) {
      r.altitude_m = ascii::parse_decimal(f[4]);
      if (!r.altitude_m) return fail(Outcome::kMalformed);
      if (!in_range(*r.altitude_m, -12000.0, 100000.0)) return fail(Outcome::kOutOfRange);
    }
    if (!in_range(v[0], -90.0, 90.0) || !in_range(v[1], -180.0, 360.0)) {
      return fail(Outcome::kOutOfRange);
    }
    r.latitude_rad = v[0] * kDegToRad;
    r.longitude_rad = wrap_pi(v[1] * kDegToRad);
    return ok(r);
  }
  if (type == "SPEED_" || type == "STDSPD") {
    std::array<double, 3> v{};  // east, north, up
    if (f.count != 5 || !numbers(f, 2, v)) return fail(Outcome::kMalformed);
    const bool is_std = type == "STDSPD";
    for (const double x : v) {
      if (!in_range(x, is_std ? 0.0 : -options.max_speed_mps, options.max_speed_mps)) {
        return fail(Outcome::kOutOfRange);
      }
    }
    if (is_std) {
      NmeaVelocityStd r;
      r.v_ned_std_mps = {v[1], v[0], v[2]};
      return ok(r);
    }
    NmeaVelocity r;
    r.v_ned_mps = {v[1], v[0], -v[2]};
    return ok(r);
  }
  if (type == "STDHRP") {
    std::array<double, 3> v{};
    if (f.count != 5 || !numbers(f, 2, v)) return fail(Outcome::kMalformed);
    for (const double x : v) {
      if (!in_range(x, 0.0, 360.0)) return fail(Outcome::kOutOfRange);
    }
    NmeaAttitudeStd r;
    r.heading_std_rad = v[0] * kDegToRad;
    r.roll_std_rad = v[1] * kDegToRad;
    r.pitch_std_rad = v[2] * kDegToRad;
    return ok(r);
  }
  if (type == "STDPOS") {
    std::array<double, 3> v{};
    if (f.count != 5 || !numbers(f, 2, v)) return fail(Outcome::kMalformed);
    for (const double x : v) {
      if (!in_range(x, 0.0, 1.0e7)) return fail(Outcome::kOutOfRange);
    }
    NmeaPositionStd r;
    r.north_std_m = v[0];
    r.east_std_m = v[1];
    r.altitude_std_m = v[2];
    return ok(r);
  }
  if (type == "STATUS" || type == "ALGSTS") {
    if (f.count != 4) return fail(Outcome::kMalformed);
    const auto lsb = ascii::parse_hex32(f[2]);
    const auto msb = ascii::parse_hex32(f[3]);
    if (!lsb || !msb) return fail(Outcome::kMalformed);
    NmeaStatus r;
    r.sentence = type == "STATUS" ? NmeaSentence::kIxseStatus : NmeaSentence::kIxseAlgsts;
    r.word = (static_cast<uint64_t>(*msb) << 32) | *lsb;
    return ok(r);
  }
  return fail(Outcome::kUnsupported);
}

Parsed parse_body(std::string_view body, const NmeaOptions& options) {
  const ascii::Fields f = ascii::split_fields(body);
  if (f.overflow) return fail(Outcome::kMalformed);
  const std::string_view address = f[0];
  for (const char c : address) {
    if (!((c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9'))) return fail(Outcome::kMalformed);
  }
  if (address.size() == 5 && address[0] != 'P' && address.substr(2) == "HDT") {
    return parse_hdt(f, address);
  }
  if (address == "PHTRO") return parse_phtro(f);
  if (address == "PIXSE") return parse_pixse(f, options);
  if (address.size() < 2) return fail(Outcome::kMalformed);
  return fail(Outcome::kUnsupported);
}

void set_time(NmeaRecord& record, const HostTime& received) {
  std::visit([&](auto& r) { r.time = Timestamps{received, std::nullopt}; }, record);
}

std::string fixed3(double v) { return ascii::format_fixed(v, 3); }

}  // namespace

std::string_view to_string(NmeaSentence sentence) {
  switch (sentence) {
    case NmeaSentence::kHdt:
      return "HDT";
    case NmeaSentence::kPhtro:
      return "PHTRO";
    case NmeaSentence::kIxseAtitud:
      return "PIXSE,ATITUD";
    case NmeaSentence::kIxseHeadng:
      return "PIXSE,HEADNG";
    case NmeaSentence::kIxsePositi:
      return "PIXSE,POSITI";
    case NmeaSentence::kIxseSpeed:
      return "PIXSE,SPEED_";
    case NmeaSentence::kIxseStdhrp:
      return "PIXSE,STDHRP";
    case NmeaSentence::kIxseStdpos:
      return "PIXSE,STDPOS";
    case NmeaSentence::kIxseStdspd:
      return "PIXSE,STDSPD";
    case NmeaSentence::kIxseStatus:
      return "PIXSE,STATUS";
    case NmeaSentence::kIxseAlgsts:
      return "PIXSE,ALGSTS";
  }
  return "?";
}

std::string NmeaOptions::validate() const {
  if (max_sentence_chars < 12 || max_sentence_chars > kMaxLimitChars) {
    return "NmeaOptions.max_sentence_chars=" + std::to_string(max_sentence_chars) +
           " outside [12, 4096]";
  }
  if (max_proprietary_sentence_chars < max_sentence_chars ||
      max_proprietary_sentence_chars > kMaxLimitChars) {
    return "NmeaOptions.max_proprietary_sentence_chars=" +
           std::to_string(max_proprietary_sentence_chars) +
           " must be within [max_sentence_chars, 4096]";
  }
  if (!(max_speed_mps > 0.0 && max_speed_mps <= 1000.0)) {
    return "NmeaOptions.max_speed_mps outside (0, 1000]";
  }
  return {};
}

struct NmeaDecoder::Impl {
  explicit Impl(NmeaOptions o)
      : options(o), framer(std::max(o.max_sentence_chars, o.max_proprietary_sentence_chars)) {}

  bool on_sentence(std::string_view sentence, const HostTime& received,
                   std::vector<NmeaRecord>& out) {
    std::string_view body;
    if (!ascii::accept_nmea_sentence(sentence, options.require_checksum, stats, body)) return false;
    Parsed parsed = parse_body(body, options);
    switch (parsed.outcome) {
      case Outcome::kRecord:
        break;
      case Outcome::kMalformed:
        ++stats.malformed;
        return false;
      case Outcome::kOutOfRange:
        ++stats.out_of_range;
        return false;
      case Outcome::kUnsupported:
        ++stats.unsupported;
        return false;
    }
    set_time(parsed.record, received);
    out.push_back(std::move(parsed.record));
    ++stats.records;
    return true;
  }

  std::size_t max_chars_for(std::string_view partial) const {
    const bool proprietary = partial.size() >= 2 && partial[1] == 'P';
    return proprietary ? options.max_proprietary_sentence_chars : options.max_sentence_chars;
  }

  NmeaOptions options;
  ascii::NmeaFramer framer;
  DecodeStats stats;
};

NmeaDecoder::NmeaDecoder(NmeaOptions options) : impl_(std::make_unique<Impl>(options)) {}
NmeaDecoder::~NmeaDecoder() = default;
NmeaDecoder::NmeaDecoder(NmeaDecoder&&) noexcept = default;
NmeaDecoder& NmeaDecoder::operator=(NmeaDecoder&&) noexcept = default;

void NmeaDecoder::feed(std::span<const uint8_t> bytes, const HostTime& received,
                       std::vector<NmeaRecord>& out) {
  Impl& impl = *impl_;
  impl.stats.bytes += bytes.size();
  impl.framer.feed(
      bytes, impl.stats,
      [&](std::string_view sentence) { return impl.on_sentence(sentence, received, out); },
      [&](std::string_view partial) { return impl.max_chars_for(partial); });
}

const DecodeStats& NmeaDecoder::stats() const { return impl_->stats; }

std::string nmea_wrap(std::string_view body) {
  std::string out;
  out.reserve(body.size() + 6);
  out += '$';
  out += body;
  out += '*';
  out += ascii::hex2(ascii::nmea_checksum(body));
  out += "\r\n";
  return out;
}

std::string encode_nmea(const NmeaRecord& record, const NmeaOptions& options) {
  struct Encoder {
    const NmeaOptions& options;
    std::string operator()(const NmeaHeading& r) const {
      if (r.sentence == NmeaSentence::kIxseHeadng) {
        return nmea_wrap("PIXSE,HEADNG," + fixed3(heading_deg_0_360(r.heading_rad)));
      }
      return nmea_wrap(std::string{r.talker[0], r.talker[1]} + "HDT," +
                       fixed3(heading_deg_0_360(r.heading_rad)) + ",T");
    }
    std::string operator()(const NmeaAttitude& r) const {
      const double roll_deg = r.roll_rad * kRadToDeg;
      const double pitch_deg = r.pitch_rad * kRadToDeg;
      if (r.sentence == NmeaSentence::kIxseAtitud) {
        const double pitch_ix = options.ixblue_pitch_positive_bow_down ? -pitch_deg : pitch_deg;
        return nmea_wrap("PIXSE,ATITUD," + fixed3(roll_deg) + "," + fixed3(pitch_ix));
      }
      return nmea_wrap("PHTRO," + ascii::format_fixed(std::abs(pitch_deg), 2) +
                       (pitch_deg > 0.0 ? ",M," : ",P,") +
                       ascii::format_fixed(std::abs(roll_deg), 2) + (roll_deg > 0.0 ? ",T" : ",B"));
    }
    std::string operator()(const NmeaPosition& r) const {
      return nmea_wrap("PIXSE,POSITI," + ascii::format_fixed(r.latitude_rad * kRadToDeg, 8) + "," +
                       ascii::format_fixed(r.longitude_rad * kRadToDeg, 8) + "," +
                       (r.altitude_m ? fixed3(*r.altitude_m) : std::string()));
    }
    std::string operator()(const NmeaVelocity& r) const {
      return nmea_wrap("PIXSE,SPEED_," + fixed3(r.v_ned_mps[1]) + "," + fixed3(r.v_ned_mps[0]) +
                       "," + fixed3(-r.v_ned_mps[2]));
    }
    std::string operator()(const NmeaAttitudeStd& r) const {
      return nmea_wrap("PIXSE,STDHRP," + fixed3(r.heading_std_rad * kRadToDeg) + "," +
                       fixed3(r.roll_std_rad * kRadToDeg) + "," +
                       fixed3(r.pitch_std_rad * kRadToDeg));
    }
    std::string operator()(const NmeaPositionStd& r) const {
      return nmea_wrap("PIXSE,STDPOS," + ascii::format_fixed(r.north_std_m, 2) + "," +
                       ascii::format_fixed(r.east_std_m, 2) + "," +
                       ascii::format_fixed(r.altitude_std_m, 2));
    }
    std::string operator()(const NmeaVelocityStd& r) const {
      return nmea_wrap("PIXSE,STDSPD," + fixed3(r.v_ned_std_mps[1]) + "," +
                       fixed3(r.v_ned_std_mps[0]) + "," + fixed3(r.v_ned_std_mps[2]));
    }
    std::string operator()(const NmeaStatus& r) const {
      std::string words;
      for (const uint32_t word :
           {static_cast<uint32_t>(r.word), static_cast<uint32_t>(r.word >> 32)}) {
        words += ',';
        for (int shift = 24; shift >= 0; shift -= 8) {
          words += ascii::hex2(static_cast<uint8_t>(word >> shift));
        }
      }
      return nmea_wrap(
          std::string(r.sentence == NmeaSentence::kIxseAlgsts ? "PIXSE,ALGSTS" : "PIXSE,STATUS") +
          words);
    }
  };
  return std::visit(Encoder{options}, record);
}

}  // namespace nav::drivers
