// Altimeter ASCII decoders and encoders (Tritech PA500, Valeport VA500, Impact Subsea ISA500,
// NMEA DBT); see altimeter.h.
#include "nav/drivers/codecs/altimeter.h"

#include <cmath>
#include <variant>

#include "ascii_text.h"
#include "nav/drivers/codecs/nmea.h"

namespace nav::drivers {
namespace {

constexpr double kMetresPerFoot = 0.3048;
constexpr double kMetresPerFathom = 1.8288;
constexpr double kPascalPerDbar = 1.0e4;
// A $PRVAT pressure outside this is no reading of a sea-water pressure sensor (the deepest ocean
// is ~11,000 dbar; gauge readings in air are near 0): the sentence is corrupt.
constexpr double kMinPlausibleDbar = -20.0;
constexpr double kMaxPlausibleDbar = 12000.0;

bool is_nmea(AltimeterProtocol protocol) {
  return protocol == AltimeterProtocol::kValeportNmea || protocol == AltimeterProtocol::kNmeaDbt;
}

bool strip_prefix(std::string_view& text, std::string_view prefix) {
  if (text.substr(0, prefix.size()) != prefix) return false;
  text.remove_prefix(prefix.size());
  return true;
}

bool strip_suffix_nocase(std::string_view& text, std::string_view suffix) {
  if (text.size() < suffix.size()) return false;
  const std::string_view tail = text.substr(text.size() - suffix.size());
  for (std::size_t i = 0; i < suffix.size(); ++i) {
    const auto lower = [](char c) { return (c >= 'A' && c <= 'Z') ? char(c - 'A' + 'a') : c; };
    if (lower(tail[i]) != lower(suffix[i])) return false;
  }
  text.remove_suffix(suffix.size());
  return true;
}

}  // namespace

std::string AltimeterFormat::validate() const {
  if (!(min_range_m >= 0.0 && min_range_m < max_range_m && std::isfinite(max_range_m))) {
    return "AltimeterFormat: need 0 <= min_range_m < max_range_m (finite)";
  }
  if (max_line_chars < 8 || max_line_chars > 256) {
    return "AltimeterFormat.max_line_chars=" + std::to_string(max_line_chars) + " outside [8, 256]";
  }
  if (prefix.size() + suffix.size() + 1 > max_line_chars) {
    return "AltimeterFormat: prefix and suffix longer than max_line_chars";
  }
  for (const char c : prefix + suffix) {
    if (c < 0x20 || c > 0x7e) return "AltimeterFormat: prefix/suffix must be printable ASCII";
  }
  return {};
}

struct AltimeterDecoder::Impl {
  explicit Impl(AltimeterFormat f)
      : format(std::move(f)), lines(format.max_line_chars), sentences(format.max_line_chars) {}

  /// Classifies a reading and emits the record.
  void emit(double value_m, std::optional<double> pressure_pa, const HostTime& received,
            std::vector<AltimeterRecord>& out) {
    AltimeterRecord record;
    record.time = Timestamps{received, std::nullopt};
    record.raw_value_m = value_m;
    record.pressure_pa = pressure_pa;
    bool no_echo = false;
    for (const double sentinel : format.no_echo_values_m) {
      if (std::abs(value_m - sentinel) <= 1e-6) no_echo = true;
    }
    if (no_echo) {
      record.status = AltimeterStatus::kNoEcho;
    } else if (value_m < format.min_range_m || value_m > format.max_range_m) {
      record.status = AltimeterStatus::kOutOfRange;
      ++stats.out_of_range;
    } else {
      record.range_m = value_m;
    }
    out.push_back(record);
    ++stats.records;
  }

  bool on_line(std::string_view line, const HostTime& received, std::vector<AltimeterRecord>& out) {
    std::string_view text = ascii::trim(line);
    const bool isa500 = format.protocol == AltimeterProtocol::kImpactSubseaIsa500;
    const std::string_view prefix = isa500 ? std::string_view(format.prefix) : "";
    const std::string_view suffix = isa500 ? std::string_view(format.suffix) : "m";
    if (!strip_prefix(text, prefix) || !strip_suffix_nocase(text, suffix)) {
      ++stats.malformed;
      return false;
    }
    const auto value = ascii::parse_decimal(ascii::trim(text));
    if (!value) {
      ++stats.malformed;
      return false;
    }
    emit(*value, std::nullopt, received, out);
    return true;
  }

  bool on_sentence(std::string_view sentence, const HostTime& received,
                   std::vector<AltimeterRecord>& out) {
    std::string_view body;
    if (!ascii::accept_nmea_sentence(sentence, format.require_checksum, stats, body)) return false;
    const ascii::Fields f = ascii::split_fields(body);
    const std::string_view address = f[0];
    if (format.protocol == AltimeterProtocol::kValeportNmea && address == "PRVAT") {
      // $PRVAT,range,M,pressure,dBar: pressure fields empty without the pressure sensor.
      const auto range = ascii::parse_decimal(f[1]);
      if (f.count != 5 || !range || f[2] != "M") {
        ++stats.malformed;
        return false;
      }
      std::optional<double> pressure_pa;
      if (!f[3].empty()) {
        const auto dbar = ascii::parse_decimal(f[3]);
        if (!dbar || !ascii::in_range(*dbar, kMinPlausibleDbar, kMaxPlausibleDbar) ||
            (f[4] != "dBar" && f[4] != "dbar")) {
          ++stats.malformed;
          return false;
        }
        pressure_pa = *dbar * kPascalPerDbar;
      }
      emit(*range, pressure_pa, received, out);
      return true;
    }
    if (format.protocol == AltimeterProtocol::kNmeaDbt && address.size() == 5 &&
        address.substr(2) == "DBT") {
      if (f.count != 7) {
        ++stats.malformed;
        return false;
      }
      // Prefer metres; fall back to feet, then fathoms (NMEA 0183 DBT).
      std::optional<double> metres;
      if (const auto m = ascii::parse_decimal(f[3]); m && f[4] == "M") {
        metres = *m;
      } else if (const auto ft = ascii::parse_decimal(f[1]); ft && f[2] == "f") {
        metres = *ft * kMetresPerFoot;
      } else if (const auto fa = ascii::parse_decimal(f[5]); fa && f[6] == "F") {
        metres = *fa * kMetresPerFathom;
      }
      if (!metres) {
        ++stats.malformed;
        return false;
      }
      emit(*metres, std::nullopt, received, out);
      return true;
    }
    ++stats.unsupported;
    return false;
  }

  AltimeterFormat format;
  ascii::LineFramer lines;
  ascii::NmeaFramer sentences;
  DecodeStats stats;
};

AltimeterDecoder::AltimeterDecoder(AltimeterFormat format)
    : impl_(std::make_unique<Impl>(std::move(format))) {}
AltimeterDecoder::~AltimeterDecoder() = default;
AltimeterDecoder::AltimeterDecoder(AltimeterDecoder&&) noexcept = default;
AltimeterDecoder& AltimeterDecoder::operator=(AltimeterDecoder&&) noexcept = default;

void AltimeterDecoder::feed(std::span<const uint8_t> bytes, const HostTime& received,
                            std::vector<AltimeterRecord>& out) {
  Impl& impl = *impl_;
  impl.stats.bytes += bytes.size();
  if (is_nmea(impl.format.protocol)) {
    impl.sentences.feed(
        bytes, impl.stats, [&](std::string_view s) { return impl.on_sentence(s, received, out); },
        [&](std::string_view) { return impl.format.max_line_chars; });
  } else {
    impl.lines.feed(bytes, impl.stats,
                    [&](std::string_view line) { return impl.on_line(line, received, out); });
  }
}

const DecodeStats& AltimeterDecoder::stats() const { return impl_->stats; }

std::string encode_altimeter(const AltimeterRecord& record, const AltimeterFormat& format) {
  const double value = record.raw_value_m;
  switch (format.protocol) {
    case AltimeterProtocol::kTritechPa500: {
      std::string text = ascii::format_fixed(value, 2);
      if (value >= 0.0 && text.size() < 6) text.insert(0, 6 - text.size(), '0');
      return text + "m\r\n";
    }
    case AltimeterProtocol::kImpactSubseaIsa500:
      return format.prefix + ascii::format_fixed(value, 3) +
             (format.suffix.empty() ? "" : " " + format.suffix) + "\r\n";
    case AltimeterProtocol::kValeportNmea:
      return nmea_wrap("PRVAT," + ascii::format_fixed(value, 3) + ",M," +
                       (record.pressure_pa
                            ? ascii::format_fixed(*record.pressure_pa / kPascalPerDbar, 3)
                            : std::string()) +
                       ",dBar");
    case AltimeterProtocol::kNmeaDbt:
      return nmea_wrap("SDDBT," + ascii::format_fixed(value / kMetresPerFoot, 1) + ",f," +
                       ascii::format_fixed(value, 1) + ",M," +
                       ascii::format_fixed(value / kMetresPerFathom, 1) + ",F");
  }
  return {};
}

}  // namespace nav::drivers
