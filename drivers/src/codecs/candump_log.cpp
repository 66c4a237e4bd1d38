// candump text log decoder; formats in candump_log.h (can-utils candump.c / lib.c sprint_*).
#include "nav/drivers/codecs/candump_log.h"

#include <algorithm>
#include <cstdio>

#include "civil_days.h"

namespace nav::drivers {
namespace {

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

bool is_digit(char c) { return c >= '0' && c <= '9'; }

/// Splits off the next whitespace-separated token.
std::string_view next_token(std::string_view& rest) {
  size_t b = 0;
  while (b < rest.size() && is_space(rest[b])) ++b;
  size_t e = b;
  while (e < rest.size() && !is_space(rest[e])) ++e;
  std::string_view token = rest.substr(b, e - b);
  rest.remove_prefix(e);
  return token;
}

bool parse_hex(std::string_view s, uint32_t& value) {
  if (s.empty() || s.size() > 8) return false;
  value = 0;
  for (char c : s) {
    const int h = hex_value(c);
    if (h < 0) return false;
    value = (value << 4) | static_cast<uint32_t>(h);
  }
  return true;
}

bool parse_unsigned(std::string_view s, size_t max_digits, int64_t& value) {
  if (s.empty() || s.size() > max_digits) return false;
  value = 0;
  for (char c : s) {
    if (!is_digit(c)) return false;
    value = value * 10 + (c - '0');
  }
  return true;
}

/// "sss.ffffff" -> µs (1..9 fraction digits, truncated to µs).
bool parse_seconds(std::string_view s, int64_t& us) {
  const size_t dot = s.find('.');
  if (dot == std::string_view::npos) return false;
  int64_t sec = 0;
  int64_t frac = 0;
  const std::string_view f = s.substr(dot + 1);
  if (!parse_unsigned(s.substr(0, dot), 12, sec) || !parse_unsigned(f, 9, frac)) return false;
  for (size_t i = f.size(); i < 6; ++i) frac *= 10;
  for (size_t i = 6; i < f.size(); ++i) frac /= 10;
  us = sec * 1'000'000 + frac;
  return true;
}

using civil::days_from_civil;

/// "YYYY-MM-DD" and "HH:MM:SS.ffffff" (candump -t A, local time; taken as UTC) -> µs.
bool parse_date_time(std::string_view date, std::string_view time, int64_t& us) {
  int64_t y = 0, mo = 0, d = 0, h = 0, mi = 0, sec_us = 0;
  if (date.size() != 10 || date[4] != '-' || date[7] != '-') return false;
  if (time.size() < 10 || time[2] != ':' || time[5] != ':') return false;
  if (!parse_unsigned(date.substr(0, 4), 4, y) || !parse_unsigned(date.substr(5, 2), 2, mo) ||
      !parse_unsigned(date.substr(8, 2), 2, d) || !parse_unsigned(time.substr(0, 2), 2, h) ||
      !parse_unsigned(time.substr(3, 2), 2, mi) || !parse_seconds(time.substr(6), sec_us)) {
    return false;
  }
  // Before 1970 would give negative times, which the log format cannot write back.
  if (y < 1970 || mo < 1 || mo > 12 || d < 1 || d > 31 || h > 23 || mi > 59 ||
      sec_us >= 61'000'000) {
    return false;
  }
  us = ((days_from_civil(y, mo, d) * 24 + h) * 60 + mi) * 60'000'000 + sec_us;
  return true;
}

/// Identifier token: 3 hex digits standard, 8 extended (flag bits -> unsupported).
CandumpLineResult parse_id(std::string_view s, CanLogFrame& f) {
  uint32_t id = 0;
  if (!parse_hex(s, id)) return CandumpLineResult::kMalformed;
  if (s.size() == 3) {
    if (id > 0x7FF) return CandumpLineResult::kMalformed;
    f.id = id;
    f.extended = false;
    return CandumpLineResult::kFrame;
  }
  if (s.size() != 8) return CandumpLineResult::kMalformed;
  if (id > 0x1FFFFFFF) return CandumpLineResult::kUnsupported;  // error frame (CAN_ERR_FLAG)
  f.id = id;
  f.extended = true;
  return CandumpLineResult::kFrame;
}

/// `ID#DATA` of the log format.
CandumpLineResult parse_log_frame(std::string_view token, CanLogFrame& f) {
  const size_t hash = token.find('#');
  if (CandumpLineResult r = parse_id(token.substr(0, hash), f); r != CandumpLineResult::kFrame) {
    return r;
  }
  std::string_view data = token.substr(hash + 1);
  if (!data.empty() && data[0] == '#') return CandumpLineResult::kUnsupported;  // CAN FD / XL
  f.remote = false;
  f.dlc = 0;
  if (!data.empty() && (data[0] == 'R' || data[0] == 'r')) {
    f.remote = true;
    data.remove_prefix(1);
    if (data.empty()) return CandumpLineResult::kFrame;
    if (data.size() != 1 || !is_digit(data[0]) || data[0] > '8') {
      return CandumpLineResult::kMalformed;
    }
    f.dlc = static_cast<uint8_t>(data[0] - '0');
    return CandumpLineResult::kFrame;
  }
  if (const size_t u = data.find('_'); u != std::string_view::npos) {
    // len8_dlc suffix (DLC 9..15 of an 8-byte frame): one hex digit, otherwise ignored.
    if (data.size() != u + 2 || hex_value(data[u + 1]) < 0) return CandumpLineResult::kMalformed;
    data = data.substr(0, u);
  }
  size_t i = 0;
  while (i < data.size()) {
    if (data[i] == '.') {
      ++i;
      continue;
    }
    if (i + 1 >= data.size() || f.dlc >= 8) return CandumpLineResult::kMalformed;
    const int hi = hex_value(data[i]);
    const int lo = hex_value(data[i + 1]);
    if (hi < 0 || lo < 0) return CandumpLineResult::kMalformed;
    f.data[f.dlc++] = static_cast<uint8_t>(hi * 16 + lo);
    i += 2;
  }
  return CandumpLineResult::kFrame;
}

/// `ID  [n]  B0 B1 ...` or `ID  [n]  remote request` of the ASCII format.
CandumpLineResult parse_ascii_frame(std::string_view id_token, std::string_view rest,
                                    CanLogFrame& f) {
  if (CandumpLineResult r = parse_id(id_token, f); r != CandumpLineResult::kFrame) return r;
  const std::string_view len = next_token(rest);
  if (len.size() == 4 && len.front() == '[' && len.back() == ']') {
    return CandumpLineResult::kUnsupported;  // CAN FD prints two length digits
  }
  if (len.size() != 3 || len.front() != '[' || len.back() != ']' || !is_digit(len[1]) ||
      len[1] > '8') {
    return CandumpLineResult::kMalformed;
  }
  f.dlc = static_cast<uint8_t>(len[1] - '0');
  f.remote = false;
  std::string_view tok = next_token(rest);
  if (tok == "remote") {
    if (next_token(rest) != "request") return CandumpLineResult::kMalformed;
    f.remote = true;
    return next_token(rest).empty() ? CandumpLineResult::kFrame : CandumpLineResult::kMalformed;
  }
  for (uint8_t k = 0; k < f.dlc; ++k) {
    if (tok.size() != 2 || hex_value(tok[0]) < 0 || hex_value(tok[1]) < 0) {
      return CandumpLineResult::kMalformed;
    }
    f.data[k] = static_cast<uint8_t>(hex_value(tok[0]) * 16 + hex_value(tok[1]));
    tok = next_token(rest);
  }
  // candump -a appends the bytes as ASCII in quotes; anything else is not ours.
  return tok.empty() || tok.front() == '\'' ? CandumpLineResult::kFrame
                                            : CandumpLineResult::kMalformed;
}

}  // namespace

CandumpLineResult parse_candump_line(std::string_view line, CanLogFrame& f, bool& has_time) {
  has_time = false;
  std::string_view rest = line;
  std::string_view tok = next_token(rest);
  if (tok.empty()) return CandumpLineResult::kBlank;
  if (tok.front() == '(') {
    int64_t us = 0;
    bool ok = false;
    if (tok.back() == ')') {
      ok = parse_seconds(tok.substr(1, tok.size() - 2), us);
    } else {  // "(YYYY-MM-DD HH:MM:SS.ffffff)"
      const std::string_view time = next_token(rest);
      ok = !time.empty() && time.back() == ')' &&
           parse_date_time(tok.substr(1), time.substr(0, time.size() - 1), us);
    }
    if (!ok) return CandumpLineResult::kMalformed;
    f.time = HostTime{us, us};
    has_time = true;
    tok = next_token(rest);
  }
  if (tok.empty()) return CandumpLineResult::kMalformed;
  f.interface_name.fill('\0');
  std::copy_n(tok.begin(), std::min<size_t>(tok.size(), f.interface_name.size() - 1),
              f.interface_name.begin());
  const std::string_view frame = next_token(rest);
  if (frame.empty()) return CandumpLineResult::kMalformed;
  if (frame.find('#') != std::string_view::npos) {
    const CandumpLineResult r = parse_log_frame(frame, f);
    if (r != CandumpLineResult::kFrame) return r;
    // candump -L may append " T"/" R" (direction) on CAN FD/XL lines; nothing else.
    const std::string_view extra = next_token(rest);
    return extra.empty() || extra == "T" || extra == "R" ? r : CandumpLineResult::kMalformed;
  }
  return parse_ascii_frame(frame, rest, f);
}

std::string format_candump_log_line(const CanLogFrame& f) {
  char buf[96];
  const int64_t us = f.time.realtime_us;
  const int64_t sec = us >= 0 ? us / 1'000'000 : -((-us + 999'999) / 1'000'000);
  const int64_t frac = us - sec * 1'000'000;
  const char* iface = f.interface_name[0] != '\0' ? f.interface_name.data() : "can0";
  int n = std::snprintf(buf, sizeof buf, "(%lld.%06lld) %.15s ", static_cast<long long>(sec),
                        static_cast<long long>(frac), iface);
  n += std::snprintf(buf + n, sizeof buf - static_cast<size_t>(n), f.extended ? "%08X#" : "%03X#",
                     static_cast<unsigned>(f.id));
  std::string out(buf, static_cast<size_t>(n));
  if (f.remote) {
    out += 'R';
    if (f.dlc > 0) out += static_cast<char>('0' + std::min<int>(f.dlc, 8));
    return out;
  }
  static constexpr char kHex[] = "0123456789ABCDEF";
  for (uint8_t k = 0; k < std::min<uint8_t>(f.dlc, 8); ++k) {
    out += kHex[f.data[k] >> 4];
    out += kHex[f.data[k] & 0xF];
  }
  return out;
}

void CandumpLogDecoder::end_line(const HostTime& received, std::vector<CanLogFrame>& out) {
  if (overlong_) {
    ++stats_.malformed;
    stats_.dropped_bytes += overlong_bytes_;
    overlong_ = false;
    overlong_bytes_ = 0;
    line_.clear();
    return;
  }
  CanLogFrame f;
  f.time = received;
  bool has_time = false;
  switch (parse_candump_line(line_, f, has_time)) {
    case CandumpLineResult::kFrame:
      ++stats_.records;
      f.line_bytes = static_cast<uint32_t>(line_.size() + 1);
      out.push_back(f);
      break;
    case CandumpLineResult::kBlank:
      break;
    case CandumpLineResult::kUnsupported:
      ++stats_.unsupported;
      stats_.dropped_bytes += line_.size() + 1;
      break;
    case CandumpLineResult::kMalformed:
      ++stats_.malformed;
      stats_.dropped_bytes += line_.size() + 1;
      break;
  }
  line_.clear();
}

void CandumpLogDecoder::feed(std::span<const uint8_t> bytes, const HostTime& received,
                             std::vector<CanLogFrame>& out) {
  stats_.bytes += bytes.size();
  for (uint8_t b : bytes) {
    if (b == '\n') {
      if (overlong_) ++overlong_bytes_;
      end_line(received, out);
      continue;
    }
    if (overlong_) {
      ++overlong_bytes_;
      continue;
    }
    if (line_.size() >= kMaxLineBytes) {
      overlong_ = true;
      overlong_bytes_ = line_.size() + 1;
      line_.clear();
      continue;
    }
    line_.push_back(static_cast<char>(b));
  }
}

void CandumpLogDecoder::finish(const HostTime& received, std::vector<CanLogFrame>& out) {
  if (overlong_ || !line_.empty()) {
    // The missing newline is not a byte of the stream.
    if (!overlong_) {
      CanLogFrame f;
      f.time = received;
      bool has_time = false;
      const CandumpLineResult r = parse_candump_line(line_, f, has_time);
      if (r == CandumpLineResult::kFrame) {
        ++stats_.records;
        f.line_bytes = static_cast<uint32_t>(line_.size());
        out.push_back(f);
      } else if (r != CandumpLineResult::kBlank) {
        ++(r == CandumpLineResult::kUnsupported ? stats_.unsupported : stats_.malformed);
        stats_.dropped_bytes += line_.size();
      }
      line_.clear();
    } else {
      ++stats_.malformed;
      stats_.dropped_bytes += overlong_bytes_;
      overlong_ = false;
      overlong_bytes_ = 0;
    }
  }
}

}  // namespace nav::drivers
