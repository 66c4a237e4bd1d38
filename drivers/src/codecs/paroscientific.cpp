// Paroscientific Digiquartz reply decoder and encoders (see paroscientific.h).
#include "nav/drivers/codecs/paroscientific.h"

#include <cmath>

#include "ascii_text.h"

namespace nav::drivers {
namespace {

std::optional<int> two_digits(std::string_view text) {
  if (text.size() != 2 || text[0] < '0' || text[0] > '9' || text[1] < '0' || text[1] > '9') {
    return std::nullopt;
  }
  return (text[0] - '0') * 10 + (text[1] - '0');
}

std::string id2(int id) {
  const int clamped = id < 0 ? 0 : (id > 99 ? 99 : id);
  std::string text(2, '0');
  text[0] = static_cast<char>('0' + clamped / 10);
  text[1] = static_cast<char>('0' + clamped % 10);
  return text;
}

bool is_letter(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }

}  // namespace

double pascal_per_unit(ParoPressureUnit unit, double custom_pa_per_unit) {
  switch (unit) {
    case ParoPressureUnit::kPsi:
      return 6894.757293168;
    case ParoPressureUnit::kHpa:
      return 100.0;
    case ParoPressureUnit::kBar:
      return 1.0e5;
    case ParoPressureUnit::kKpa:
      return 1.0e3;
    case ParoPressureUnit::kMpa:
      return 1.0e6;
    case ParoPressureUnit::kInHg:
      return 3386.389;
    case ParoPressureUnit::kMmHg:
      return 133.322368;
    case ParoPressureUnit::kMH2O:
      return 9806.65;
    case ParoPressureUnit::kDbar:
      return 1.0e4;
    case ParoPressureUnit::kPascal:
      return 1.0;
    case ParoPressureUnit::kCustom:
      return custom_pa_per_unit;
  }
  return 1.0;
}

std::string ParoOptions::validate() const {
  if (unit == ParoPressureUnit::kCustom &&
      !(custom_pa_per_unit > 0.0 && std::isfinite(custom_pa_per_unit))) {
    return "ParoOptions.custom_pa_per_unit must be > 0 with unit kCustom";
  }
  if (source_id && (*source_id < 1 || *source_id > 98)) {
    return "ParoOptions.source_id=" + std::to_string(*source_id) + " outside [1, 98]";
  }
  if (!(min_pressure_pa < max_pressure_pa)) {
    return "ParoOptions.min_pressure_pa must be < max_pressure_pa";
  }
  if (max_line_chars < 8 || max_line_chars > 256) {
    return "ParoOptions.max_line_chars=" + std::to_string(max_line_chars) + " outside [8, 256]";
  }
  return {};
}

struct ParoDecoder::Impl {
  explicit Impl(ParoOptions o) : options(o), framer(o.max_line_chars) {}

  bool on_line(std::string_view line, const HostTime& received, std::vector<ParoRecord>& out) {
    // Replies may be preceded by blanks on a multi-drop line; the '*' starts the record.
    const std::string_view text = ascii::trim(line);
    if (text.size() < 6 || text[0] != '*') {
      ++stats.malformed;
      return false;
    }
    const auto destination = two_digits(text.substr(1, 2));
    const auto source = two_digits(text.substr(3, 2));
    if (!destination || !source) {
      ++stats.malformed;
      return false;
    }
    const std::string_view data = ascii::trim(text.substr(5));
    if (!data.empty() && is_letter(data[0])) {
      ++stats.unsupported;  // a command (e.g. "*0100P3") or a text reply (e.g. "*0001UN=1")
      return false;
    }
    const auto value = ascii::parse_decimal(data);
    if (!value) {
      ++stats.malformed;
      return false;
    }
    if (options.source_id && *source != *options.source_id) {
      ++stats.unsupported;
      return false;
    }
    const double pressure_pa = *value * pascal_per_unit(options.unit, options.custom_pa_per_unit);
    if (!(pressure_pa >= options.min_pressure_pa && pressure_pa <= options.max_pressure_pa)) {
      ++stats.out_of_range;
      return false;
    }
    out.push_back(
        ParoRecord{Timestamps{received, std::nullopt}, *destination, *source, pressure_pa});
    ++stats.records;
    return true;
  }

  ParoOptions options;
  ascii::LineFramer framer;
  DecodeStats stats;
};

ParoDecoder::ParoDecoder(ParoOptions options) : impl_(std::make_unique<Impl>(options)) {}
ParoDecoder::~ParoDecoder() = default;
ParoDecoder::ParoDecoder(ParoDecoder&&) noexcept = default;
ParoDecoder& ParoDecoder::operator=(ParoDecoder&&) noexcept = default;

void ParoDecoder::feed(std::span<const uint8_t> bytes, const HostTime& received,
                       std::vector<ParoRecord>& out) {
  Impl& impl = *impl_;
  impl.stats.bytes += bytes.size();
  impl.framer.feed(bytes, impl.stats,
                   [&](std::string_view line) { return impl.on_line(line, received, out); });
}

const DecodeStats& ParoDecoder::stats() const { return impl_->stats; }

std::string encode_paro_reply(const ParoRecord& record, const ParoOptions& options, int decimals) {
  const double value =
      record.pressure_pa / pascal_per_unit(options.unit, options.custom_pa_per_unit);
  std::string out;
  out.reserve(32);
  out += '*';
  out += id2(record.destination_id);
  out += id2(record.source_id);
  out += ascii::format_fixed(value, decimals);
  out += "\r\n";
  return out;
}

std::string encode_paro_command(int transmitter_id, const std::string& command) {
  std::string out;
  out.reserve(command.size() + 8);
  out += '*';
  out += id2(transmitter_id);
  out += "00";
  out += command;
  out += "\r\n";
  return out;
}

}  // namespace nav::drivers
