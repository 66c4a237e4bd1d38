// Strict number parsing/formatting and NMEA sentence validation shared by the ASCII codecs.
#include "ascii_text.h"

#include <charconv>
#include <cmath>

namespace nav::drivers::ascii {

std::optional<double> parse_decimal(std::string_view text) {
  std::size_t i = 0;
  bool negative = false;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) {
    negative = text[i] == '-';
    ++i;
  }
  const std::size_t start = i;
  std::size_t digits = 0;
  bool point = false;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (c >= '0' && c <= '9') {
      ++digits;
    } else if (c == '.' && !point) {
      point = true;
    } else {
      return std::nullopt;
    }
  }
  if (digits == 0 || digits > 80) return std::nullopt;
  double value = 0.0;
  const char* first = text.data() + start;
  const char* last = text.data() + text.size();
  const auto result = std::from_chars(first, last, value, std::chars_format::fixed);
  if (result.ec != std::errc() || result.ptr != last || !std::isfinite(value)) {
    return std::nullopt;
  }
  return negative ? -value : value;
}

std::optional<uint32_t> parse_hex32(std::string_view text) {
  if (text.empty() || text.size() > 8) return std::nullopt;
  uint32_t value = 0;
  const auto result = std::from_chars(text.data(), text.data() + text.size(), value, 16);
  if (result.ec != std::errc() || result.ptr != text.data() + text.size()) return std::nullopt;
  return value;
}

std::string_view trim(std::string_view text) {
  while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  return text;
}

std::string format_fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "0";
  std::array<char, 64> buffer{};
  auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value,
                              std::chars_format::fixed, decimals);
  if (result.ec != std::errc()) return "0";
  std::string text(buffer.data(), result.ptr);
  // "-0.000" would decode as 0 anyway; keep the text canonical for byte-exact round trips.
  if (text.front() == '-' && text.find_first_not_of("-0.") == std::string::npos) text.erase(0, 1);
  return text;
}

std::string hex2(uint8_t byte) {
  static constexpr char kDigits[] = "0123456789ABCDEF";
  return std::string{kDigits[byte >> 4], kDigits[byte & 0x0f]};
}

Fields split_fields(std::string_view text, char separator) {
  Fields fields;
  std::size_t begin = 0;
  while (true) {
    const std::size_t end = text.find(separator, begin);
    if (fields.count == Fields::kMaxFields) {
      fields.overflow = true;
      return fields;
    }
    fields.field[fields.count++] =
        text.substr(begin, end == std::string_view::npos ? std::string_view::npos : end - begin);
    if (end == std::string_view::npos) return fields;
    begin = end + 1;
  }
}

uint8_t nmea_checksum(std::string_view body) {
  uint8_t sum = 0;
  for (const char c : body) sum ^= static_cast<uint8_t>(c);
  return sum;
}

SentenceCheck check_nmea_sentence(std::string_view sentence, std::string_view& body) {
  if (sentence.size() < 2 || (sentence[0] != '$' && sentence[0] != '!')) {
    return SentenceCheck::kMalformed;
  }
  const std::string_view after_start = sentence.substr(1);
  const std::size_t star = after_start.find('*');
  if (star == std::string_view::npos) {
    body = after_start;
    return SentenceCheck::kMissingChecksum;
  }
  body = after_start.substr(0, star);
  const std::string_view hex = after_start.substr(star + 1);
  // NMEA 0183 section 5.3.1: the checksum field is exactly two hex characters after '*'.
  if (hex.size() != 2) return SentenceCheck::kMalformed;
  const auto expected = parse_hex32(hex);
  if (!expected) return SentenceCheck::kMalformed;
  return *expected == nmea_checksum(body) ? SentenceCheck::kOk : SentenceCheck::kBadChecksum;
}

bool accept_nmea_sentence(std::string_view sentence, bool require_checksum, DecodeStats& stats,
                          std::string_view& body) {
  switch (check_nmea_sentence(sentence, body)) {
    case SentenceCheck::kOk:
      return true;
    case SentenceCheck::kBadChecksum:
      ++stats.checksum_failures;
      return false;
    case SentenceCheck::kMalformed:
      ++stats.malformed;
      return false;
    case SentenceCheck::kMissingChecksum:
      if (require_checksum) {
        ++stats.malformed;
        return false;
      }
      return true;
  }
  return false;
}

}  // namespace nav::drivers::ascii
