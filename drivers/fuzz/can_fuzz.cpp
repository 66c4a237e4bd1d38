// libFuzzer target for the CAN codecs. The input is a candump text log: whole vs three-chunk
// decoding must agree and the counters add up; every parsed frame must survive
// format -> parse unchanged; frames are decoded with a fixed signal table (Intel and Motorola,
// signed, odd lengths, multiplexed, time counter, a message dated by another), and every decoded
// value must re-encode to the same raw bits; sensor times feed a ClockMapping whose outputs
// must stay finite. The bytes are also read directly as (id, length, payload) records for the
// signal decoder.
#include <cmath>
#include <cstdlib>
#include <span>
#include <vector>

#include "nav/drivers/codecs/can_signals.h"
#include "nav/drivers/codecs/candump_log.h"
#include "nav/drivers/time/clock_mapping.h"

namespace {

using namespace nav::drivers;

void check(bool condition) {
  if (!condition) std::abort();
}

CanSignalSpec sig(const char* name, uint32_t start, uint32_t length, CanByteOrder order,
                  bool is_signed, double scale, const char* unit) {
  CanSignalSpec s;
  s.name = name;
  s.start_bit = start;
  s.length = length;
  s.byte_order = order;
  s.is_signed = is_signed;
  s.scale = scale;
  s.unit = unit;
  return s;
}

std::vector<CanMessageSpec> table() {
  constexpr auto kI = CanByteOrder::kIntel;
  constexpr auto kM = CanByteOrder::kMotorola;
  CanMessageSpec dvl{"dvl", 0x200, false, 8, "", {}, "", ""};
  dvl.signals = {sig("vx", 0, 16, kI, true, 0.1, "mm/s"), sig("vy", 16, 16, kI, true, 0.1, "mm/s"),
                 sig("t", 32, 32, kI, false, 1.0, "ms")};
  dvl.signals[0].invalid_raw = 0x8000;
  dvl.signals[0].min = -5000;
  dvl.signals[0].max = 5000;
  dvl.signals[2].time_of_validity = true;
  CanMessageSpec fog{"fog", 0x18FF1002, true, 8, "", {}, "", ""};
  fog.signals = {sig("rx", 7, 20, kM, true, 1e-4, "deg/s"),
                 sig("ry", 19, 20, kM, true, 1e-4, "deg/s"),
                 sig("rz", 47, 20, kM, true, 1e-4, "deg/s"), sig("st", 59, 4, kM, false, 1, "")};
  CanMessageSpec moto{"moto", 496, false, 8, "", {}, "", ""};
  moto.signals = {sig("temp", 0, 12, kM, true, 0.01, "K"), sig("r", 6, 6, kM, false, 0.1, "m"),
                  sig("en", 7, 1, kM, false, 1, "")};
  moto.signals[0].offset = 250;
  moto.signals.push_back(sig("seq", 24, 8, kI, false, 1, ""));  // dated by "us" (time_from)
  moto.time_from = "us";
  moto.time_match = "seq";
  CanMessageSpec mux{"mux", 0x202, false, 4, "sel", {}, "", ""};
  mux.signals = {sig("sel", 0, 2, kI, false, 1, ""), sig("a", 2, 29, kI, false, 1, "mm"),
                 sig("b", 2, 13, kI, true, 0.5, "cm"), sig("c", 31, 1, kI, false, 1, "")};
  mux.signals[1].multiplexer_value = 0;
  mux.signals[2].multiplexer_value = 1;
  mux.signals[2].invalid_raw = 0x1000;
  CanMessageSpec us{"us", 0x18FF1003, true, 4, "", {sig("t", 7, 16, kM, false, 1.0, "us")}, "", ""};
  us.signals[0].time_of_validity = true;
  us.signals.push_back(sig("seq", 23, 8, kM, false, 1, ""));
  return {dvl, fog, moto, mux, us};
}

/// Every value present in `m` re-encodes to the raw bits it was decoded from.
void check_round_trip(CanSignalDecoder& decoder, const CanDecodedMessage& m) {
  std::vector<CanSignalInput> in;
  for (const CanSignalValue& v : m.signals) {
    if (v.value_si) in.push_back({v.spec->name, *v.value_si});
  }
  const auto bytes = encode_can_message(*m.spec, in);
  check(bytes.has_value() && bytes->size() == m.spec->dlc);
  CanDecodedMessage again;
  check(decoder.decode(m.id, m.extended, *bytes, m.time, again));
  for (const CanSignalValue& v : m.signals) {
    if (!v.value_si) continue;
    bool found = false;
    for (const CanSignalValue& w : again.signals) {
      if (w.spec != v.spec) continue;
      found = true;
      check(w.raw == v.raw && w.value_si == v.value_si);
    }
    check(found);
  }
}

void check_frame_format(const CanLogFrame& f) {
  CanLogFrame g;
  bool has_time = false;
  check(parse_candump_line(format_candump_log_line(f), g, has_time) == CandumpLineResult::kFrame);
  check(has_time && g.id == f.id && g.extended == f.extended && g.remote == f.remote);
  check(g.dlc == f.dlc && g.data == f.data && g.time.realtime_us == f.time.realtime_us);
}

std::vector<CanLogFrame> parse_log(std::span<const uint8_t> data, size_t a, size_t b,
                                   DecodeStats& stats) {
  CandumpLogDecoder log;
  std::vector<CanLogFrame> out;
  log.feed(data.subspan(0, a), {}, out);
  log.feed(data.subspan(a, b - a), {}, out);
  log.feed(data.subspan(b), {}, out);
  log.finish({}, out);
  stats = log.stats();
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  static std::vector<CanMessageSpec>* specs = new std::vector<CanMessageSpec>(table());
  const std::span<const uint8_t> data(bytes, size);
  const size_t a = size == 0 ? 0 : bytes[0] % (size + 1);
  const size_t b = a + (size - a == 0 ? 0 : bytes[size - 1] % (size - a + 1));
  DecodeStats whole_stats, chunked_stats;
  const auto frames = parse_log(data, 0, 0, whole_stats);
  const auto chunked = parse_log(data, a, b, chunked_stats);
  check(whole_stats.to_json() == chunked_stats.to_json());
  check(frames.size() == chunked.size() && whole_stats.records == frames.size());
  check(whole_stats.bytes == size && whole_stats.dropped_bytes <= size);

  CanSignalDecoder decoder(*specs);
  ClockMappingOptions options;
  options.sensor_modulus_us = int64_t{1} << 32;
  ClockMapping clock(options);
  CanDecodedMessage m;
  for (const CanLogFrame& f : frames) {
    check(f.dlc <= 8 && f.id <= (f.extended ? 0x1FFFFFFFu : 0x7FFu));
    check_frame_format(f);
    if (f.remote || !decoder.decode(f.id, f.extended, f.payload(), {f.time, {}}, m)) continue;
    check_round_trip(decoder, m);
    if (m.time.sensor_time_us && *m.time.sensor_time_us >= 0 &&
        *m.time.sensor_time_us < options.sensor_modulus_us) {
      clock.update(*m.time.sensor_time_us, f.time.realtime_us);
      if (const auto host = clock.to_host_us(*m.time.sensor_time_us)) {
        const auto u = clock.uncertainty_us(*m.time.sensor_time_us);
        check(u.has_value() && std::isfinite(*u) && *u > 0.0);
      }
    }
  }
  // The same bytes as binary frames: id (2 bytes), flags/length (1 byte), up to 8 data bytes.
  for (size_t i = 0; i + 3 <= size;) {
    const bool extended = bytes[i + 2] & 0x80;
    uint32_t id = static_cast<uint32_t>(bytes[i] | (bytes[i + 1] << 8));
    if (extended)
      id = 0x18FF0000u | (id & 0x1FFF);
    else
      id &= 0x7FF;
    const size_t len = std::min<size_t>(bytes[i + 2] & 0x0F, size - i - 3);
    const std::span<const uint8_t> payload(bytes + i + 3, std::min<size_t>(len, 8));
    if (decoder.decode(id, extended, payload, {}, m)) check_round_trip(decoder, m);
    i += 3 + len;
  }
  const DecodeStats& s = decoder.stats();
  check(s.dropped_bytes <= s.bytes && s.out_of_range <= s.records);
  return 0;
}
