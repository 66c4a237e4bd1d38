#pragma once
// Internal helpers of the ASCII codecs (NMEA 0183, KVH DSP-3000, Paroscientific, altimeters):
// strict locale-free number parsing and formatting, field splitting, and two bounded byte
// framers that resynchronise after garbage and account for every dropped byte.
//
// Byte accounting (all ASCII codecs): a byte either belongs to an emitted record (its text and
// its line terminator, a CR LF pair counting as one terminator) or is counted in
// DecodeStats::dropped_bytes. The framers work byte by byte, so the output and the counters do
// not depend on how the stream is chunked.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "nav/drivers/codecs/decode_stats.h"

namespace nav::drivers::ascii {

/// Strict decimal number: optional sign, digits, optional '.' and digits, at least one digit.
/// No exponent, no "nan"/"inf", no spaces. Empty optional when the text is anything else.
std::optional<double> parse_decimal(std::string_view text);
/// 1..8 hexadecimal digits (either case) -> value.
std::optional<uint32_t> parse_hex32(std::string_view text);
inline bool in_range(double v, double lo, double hi) { return v >= lo && v <= hi; }  ///< NaN: no
/// Removes leading and trailing spaces and tabs.
std::string_view trim(std::string_view text);
/// Fixed-point text of `value` with `decimals` digits after the point (locale-free).
std::string format_fixed(double value, int decimals);
/// Two upper-case hexadecimal digits of `byte`.
std::string hex2(uint8_t byte);
/// Comma-separated fields of a sentence body, at most kMaxFields (more -> `overflow`).
struct Fields {
  static constexpr std::size_t kMaxFields = 32;
  std::array<std::string_view, kMaxFields> field{};
  std::size_t count = 0;
  bool overflow = false;

  std::string_view operator[](std::size_t i) const { return i < count ? field[i] : ""; }
};
Fields split_fields(std::string_view text, char separator = ',');
/// NMEA 0183 checksum: XOR of every character between '$' (or '!') and '*', exclusive.
uint8_t nmea_checksum(std::string_view body);

enum class SentenceCheck { kOk, kBadChecksum, kMalformed, kMissingChecksum };
/// Validates one framed NMEA sentence `$<body>[*hh]` (without its line terminator) and returns
/// the body between the start character and '*' in `body`.
SentenceCheck check_nmea_sentence(std::string_view sentence, std::string_view& body);
/// check_nmea_sentence with the counting of the NMEA codecs: a bad checksum counts in
/// `stats.checksum_failures`; a malformed sentence, or one without checksum when
/// `require_checksum`, counts in `stats.malformed`. Returns whether `body` may be parsed.
bool accept_nmea_sentence(std::string_view sentence, bool require_checksum, DecodeStats& stats,
                          std::string_view& body);

/// Line framer for protocols whose records are single text lines ended by CR, LF or CR LF
/// (KVH, Paroscientific, plain altimeter strings). `on_line(std::string_view) -> bool` is called
/// for each non-empty line without its terminator and returns whether the line became a record;
/// the framer counts the bytes of refused lines as dropped (the caller counts why). A byte that
/// is neither printable ASCII nor a terminator ends the current line as garbage; a line longer
/// than the limit is dropped up to its terminator and counted malformed.
class LineFramer {
 public:
  explicit LineFramer(std::size_t max_line_chars) : max_line_chars_(max_line_chars) {
    line_.reserve(max_line_chars);
  }

  template <typename OnLine>
  void feed(std::span<const uint8_t> bytes, DecodeStats& stats, OnLine&& on_line) {
    for (const uint8_t byte : bytes) feed_byte(byte, stats, on_line);
  }

 private:
  template <typename OnLine>
  void feed_byte(uint8_t byte, DecodeStats& stats, OnLine& on_line) {
    const bool lf_after_cr = byte == '\n' && previous_was_cr_;
    previous_was_cr_ = false;
    if (byte == '\r' || byte == '\n') {
      if (lf_after_cr) {
        if (!previous_accepted_) ++stats.dropped_bytes;
        return;
      }
      previous_was_cr_ = byte == '\r';
      previous_accepted_ = false;
      if (overflowed_) {
        stats.dropped_bytes += overflow_bytes_ + 1;
        overflowed_ = false;
        overflow_bytes_ = 0;
      } else if (line_.empty()) {
        ++stats.dropped_bytes;
      } else {
        previous_accepted_ = on_line(std::string_view(line_));
        if (!previous_accepted_) stats.dropped_bytes += line_.size() + 1;
      }
      line_.clear();
      return;
    }
    if (byte < 0x20 || byte > 0x7e) {
      // Binary garbage: what came before it on this line cannot be a record.
      stats.dropped_bytes += (overflowed_ ? overflow_bytes_ : line_.size()) + 1;
      if (!line_.empty() && !overflowed_) ++stats.malformed;
      overflowed_ = false;
      overflow_bytes_ = 0;
      line_.clear();
      return;
    }
    if (overflowed_) {
      ++overflow_bytes_;
      return;
    }
    if (line_.size() >= max_line_chars_) {
      ++stats.malformed;
      overflowed_ = true;
      overflow_bytes_ = line_.size() + 1;
      line_.clear();
      return;
    }
    line_.push_back(static_cast<char>(byte));
  }

  std::size_t max_line_chars_;
  std::string line_;
  bool overflowed_ = false;
  std::size_t overflow_bytes_ = 0;
  bool previous_was_cr_ = false;
  bool previous_accepted_ = false;
};

/// Framer for NMEA 0183 sentences (IEC 61162-1 / NMEA 0183 v4.1 section 5.3): a sentence starts
/// at '$' or '!' and ends at CR or LF; bytes outside sentences are dropped. A start character
/// inside a sentence truncates the previous one (malformed). `on_sentence(std::string_view)`
/// receives the sentence from its start character, without terminator, and returns whether it
/// became a record. `max_chars_for(std::string_view partial)` gives the length limit that
/// applies to the sentence seen so far (proprietary sentences may have a longer limit).
class NmeaFramer {
 public:
  explicit NmeaFramer(std::size_t buffer_chars) : buffer_chars_(buffer_chars) {
    sentence_.reserve(buffer_chars);
  }

  template <typename OnSentence, typename MaxChars>
  void feed(std::span<const uint8_t> bytes, DecodeStats& stats, OnSentence&& on_sentence,
            MaxChars&& max_chars_for) {
    for (const uint8_t byte : bytes) feed_byte(byte, stats, on_sentence, max_chars_for);
  }

 private:
  template <typename OnSentence, typename MaxChars>
  void feed_byte(uint8_t byte, DecodeStats& stats, OnSentence& on_sentence,
                 MaxChars& max_chars_for) {
    const bool lf_after_cr = byte == '\n' && previous_was_cr_;
    previous_was_cr_ = false;
    if (byte == '$' || byte == '!') {
      if (in_sentence_) {
        ++stats.malformed;
        stats.dropped_bytes += sentence_.size();
      }
      sentence_.assign(1, static_cast<char>(byte));
      in_sentence_ = true;
      return;
    }
    if (!in_sentence_) {
      if (!(lf_after_cr && previous_accepted_)) ++stats.dropped_bytes;
      return;
    }
    if (byte == '\r' || byte == '\n') {
      previous_was_cr_ = byte == '\r';
      // The limit counts the terminator pair as NMEA 0183 does (82 = '$' + 79 + CR LF).
      if (sentence_.size() + 2 > max_chars_for(std::string_view(sentence_))) {
        ++stats.malformed;
        previous_accepted_ = false;
      } else {
        previous_accepted_ = on_sentence(std::string_view(sentence_));
      }
      if (!previous_accepted_) stats.dropped_bytes += sentence_.size() + 1;
      in_sentence_ = false;
      sentence_.clear();
      return;
    }
    if (byte < 0x20 || byte > 0x7e || sentence_.size() >= buffer_chars_) {
      ++stats.malformed;
      stats.dropped_bytes += sentence_.size() + 1;
      in_sentence_ = false;
      previous_accepted_ = false;
      sentence_.clear();
      return;
    }
    sentence_.push_back(static_cast<char>(byte));
  }

  std::size_t buffer_chars_;
  std::string sentence_;
  bool in_sentence_ = false;
  bool previous_was_cr_ = false;
  bool previous_accepted_ = false;
};

}  // namespace nav::drivers::ascii
