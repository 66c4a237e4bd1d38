// CAN signal codec (DBC model): bit layouts checked by hand and against the cantools example,
// against an independent 64-bit-word reference, decode counters, multiplexing, validation.

#include "nav/drivers/codecs/can_signals.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace nav::drivers {
namespace {

CanSignalSpec sig(std::string name, uint32_t start, uint32_t length, CanByteOrder order,
                  bool is_signed = false, double scale = 1.0, double offset = 0.0,
                  std::string unit = "") {
  CanSignalSpec s;
  s.name = std::move(name);
  s.start_bit = start;
  s.length = length;
  s.byte_order = order;
  s.is_signed = is_signed;
  s.scale = scale;
  s.offset = offset;
  s.unit = std::move(unit);
  return s;
}

constexpr auto kIntel = CanByteOrder::kIntel;
constexpr auto kMotorola = CanByteOrder::kMotorola;

/// cantools' tests/files/dbc/motohawk.dbc ExampleMessage (frame id 496):
///  SG_ Temperature : 0|12@0- (0.01,250) [229.52|270.47] "degK"
///  SG_ AverageRadius : 6|6@0+ (0.1,0) [0|5] "m"
///  SG_ Enable : 7|1@0+ (1,0) [0|0] "-"
CanMessageSpec motohawk() {
  CanMessageSpec m;
  m.name = "ExampleMessage";
  m.id = 496;
  m.dlc = 8;
  CanSignalSpec temperature = sig("Temperature", 0, 12, kMotorola, true, 0.01, 250.0);
  temperature.min = 229.52;
  temperature.max = 270.47;
  CanSignalSpec radius = sig("AverageRadius", 6, 6, kMotorola, false, 0.1, 0.0, "m");
  radius.min = 0.0;
  radius.max = 5.0;
  m.signals = {temperature, radius, sig("Enable", 7, 1, kMotorola)};
  return m;
}

TEST(CanSignals, MotohawkExampleEncodesAsCantoolsDocuments) {
  // cantools README / examples/hello_world.py: {Temperature 250.1, AverageRadius 3.2,
  // Enable 1} encodes to c001400000000000.
  const std::vector<CanSignalInput> in = {
      {"Temperature", 250.1}, {"AverageRadius", 3.2}, {"Enable", 1.0}};
  const auto bytes = encode_can_message(motohawk(), in);
  ASSERT_TRUE(bytes.has_value());
  EXPECT_EQ(*bytes, (std::vector<uint8_t>{0xC0, 0x01, 0x40, 0, 0, 0, 0, 0}));

  CanSignalDecoder decoder({motohawk()});
  const auto msg = decoder.decode(496, false, *bytes, Timestamps{});
  ASSERT_TRUE(msg.has_value());
  EXPECT_NEAR(*msg->value("Temperature"), 250.1, 1e-9);
  EXPECT_NEAR(*msg->value("AverageRadius"), 3.2, 1e-9);
  EXPECT_EQ(*msg->value("Enable"), 1.0);
  EXPECT_EQ(msg->signals[0].raw, 10u);  // (250.1 - 250) / 0.01
}

TEST(CanSignals, MotorolaNegativeValueStraddlesThreeBytes) {
  // Temperature raw -1 (0xFFF): bit 0 of byte 0, all of byte 1, bits 7..5 of byte 2.
  const CanSignalSpec t = sig("t", 0, 12, kMotorola, true);
  std::vector<uint8_t> data(8, 0);
  can_insert_raw(t, 0xFFF, data);
  EXPECT_EQ(data, (std::vector<uint8_t>{0x01, 0xFF, 0xE0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(can_extract_raw(t, data), 0xFFFu);
  EXPECT_EQ(can_signal_end_byte(t), 3u);
}

TEST(CanSignals, HandCheckedIntelLayouts) {
  const std::vector<uint8_t> data = {0x34, 0x12, 0xF0, 0xAB, 0, 0, 0, 0x80};
  EXPECT_EQ(can_extract_raw(sig("a", 0, 16, kIntel), data), 0x1234u);
  // 12 bits from bit 20: high nibble of byte 2 (0xF) then byte 3 (0xAB) -> 0xABF.
  EXPECT_EQ(can_extract_raw(sig("b", 20, 12, kIntel), data), 0xABFu);
  EXPECT_EQ(can_extract_raw(sig("c", 63, 1, kIntel), data), 1u);
  EXPECT_EQ(can_extract_raw(sig("d", 4, 8, kIntel), data), 0x23u);  // crosses bytes 0..1
  // The same 12 bits signed: 0xABF - 0x1000 = -1345.
  CanMessageSpec m{"m", 0x10, false, 8, "", {sig("b", 20, 12, kIntel, true)}, "", ""};
  CanSignalDecoder decoder({m});
  EXPECT_EQ(*decoder.decode(0x10, false, data, {})->value("b"), -1345.0);
}

TEST(CanSignals, HandCheckedMotorolaLayouts) {
  const std::vector<uint8_t> data = {0x12, 0x34, 0x56, 0x78, 0x9A, 0xBC, 0xDE, 0xF0};
  EXPECT_EQ(can_extract_raw(sig("a", 7, 16, kMotorola), data), 0x1234u);
  EXPECT_EQ(can_extract_raw(sig("b", 39, 16, kMotorola), data), 0x9ABCu);  // bytes 4..5
  EXPECT_EQ(can_extract_raw(sig("c", 7, 64, kMotorola), data), 0x123456789ABCDEF0u);
  // 3|8: bits 3..0 of byte 0 then bits 7..4 of byte 1 -> 0x23.
  EXPECT_EQ(can_extract_raw(sig("d", 3, 8, kMotorola), data), 0x23u);
  // Inside one byte both orders agree: 7|8@0 == 0|8@1, 5|3@0 == 3|3@1.
  EXPECT_EQ(can_extract_raw(sig("e", 7, 8, kMotorola), data),
            can_extract_raw(sig("f", 0, 8, kIntel), data));
  EXPECT_EQ(can_extract_raw(sig("g", 5, 3, kMotorola), data),
            can_extract_raw(sig("h", 3, 3, kIntel), data));
}

/// Independent reference: the payload as one 64-bit word. Intel: little-endian word, the
/// signal is `length` bits from bit `start`. Motorola: big-endian word (byte 0 most
/// significant), where DBC bit b is word bit 8 * (7 - b / 8) + b % 8 and the signal runs
/// downwards from its MSB.
uint64_t reference_extract(const CanSignalSpec& s, const std::array<uint8_t, 8>& d) {
  uint64_t le = 0;
  uint64_t be = 0;
  for (int i = 0; i < 8; ++i) {
    le |= static_cast<uint64_t>(d[i]) << (8 * i);
    be = (be << 8) | d[i];
  }
  const uint64_t mask = s.length == 64 ? ~uint64_t{0} : (uint64_t{1} << s.length) - 1;
  if (s.byte_order == kIntel) return (le >> s.start_bit) & mask;
  const uint32_t msb_word_bit = 8 * (7 - s.start_bit / 8) + s.start_bit % 8;
  return (be >> (msb_word_bit + 1 - s.length)) & mask;
}

TEST(CanSignals, AgreesWithWordReferenceForEveryLayout) {
  std::mt19937_64 rng(7);
  std::array<uint8_t, 8> data{};
  size_t layouts = 0;
  for (CanByteOrder order : {kIntel, kMotorola}) {
    for (uint32_t start = 0; start < 64; ++start) {
      for (uint32_t length = 1; length <= 64; ++length) {
        CanSignalSpec s = sig("s", start, length, order);
        CanMessageSpec m{"m", 1, false, 8, "", {s}, "", ""};
        if (!validate_can_messages({m}).empty()) continue;  // runs past the frame
        ++layouts;
        for (int trial = 0; trial < 3; ++trial) {
          for (auto& b : data) b = static_cast<uint8_t>(rng());
          ASSERT_EQ(can_extract_raw(s, data), reference_extract(s, data))
              << "start " << start << " length " << length;
          // Insert a new value: read back exactly, every other bit unchanged.
          const uint64_t mask = length == 64 ? ~uint64_t{0} : (uint64_t{1} << length) - 1;
          const uint64_t raw = rng() & mask;
          std::array<uint8_t, 8> changed = data;
          can_insert_raw(s, raw, changed);
          ASSERT_EQ(can_extract_raw(s, changed), raw);
          can_insert_raw(s, reference_extract(s, data), changed);
          ASSERT_EQ(changed, data);
        }
      }
    }
  }
  EXPECT_EQ(layouts, 2u * 2080u);  // sum over start of (64 - start) layouts per byte order
}

TEST(CanSignals, RoundTripsSignedOddLengthsAndScales) {
  CanMessageSpec m{"m", 0x321, false, 8, "", {}, "", ""};
  m.signals = {sig("a_mps", 3, 13, kIntel, true, 0.5, 0.0, "mm/s"),
               sig("b_rad", 29, 20, kMotorola, true, 0.001, 0.0, "deg"),
               sig("c_m", 59, 3, kMotorola, false, 1.0, -2.0, "m"),
               sig("d", 16, 5, kIntel, false, 2.0, 1.0)};
  ASSERT_EQ(validate_can_messages({m}), "");
  CanSignalDecoder decoder({m});
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> a(-2.0, 2.0), b(-500.0, 500.0);
  for (int i = 0; i < 500; ++i) {
    const double a_mps = std::round(a(rng) * 2000.0) / 2000.0;  // multiples of 0.5 mm/s
    const double b_rad = std::round(b(rng) * 1000.0) / 1000.0 * std::numbers::pi / 180.0;
    const double c_m = static_cast<double>(rng() % 8) - 2.0;
    const double d = 2.0 * static_cast<double>(rng() % 32) + 1.0;
    const std::vector<CanSignalInput> in = {
        {"a_mps", a_mps}, {"b_rad", b_rad}, {"c_m", c_m}, {"d", d}};
    const auto bytes = encode_can_message(m, in);
    ASSERT_TRUE(bytes);
    const auto out = decoder.decode(0x321, false, *bytes, {});
    ASSERT_TRUE(out);
    EXPECT_NEAR(*out->value("a_mps"), a_mps, 1e-12);
    EXPECT_NEAR(*out->value("b_rad"), b_rad, 1e-12);
    EXPECT_EQ(*out->value("c_m"), c_m);
    EXPECT_EQ(*out->value("d"), d);
  }
  EXPECT_EQ(decoder.stats().records, 500u);
}

TEST(CanSignals, EncoderSaturatesAndRejectsUnknownNames) {
  CanMessageSpec m{"m", 0x1, false, 2, "", {sig("s", 0, 8, kIntel, true), sig("u", 8, 4, kIntel)},
                   "",  ""};
  const std::vector<CanSignalInput> big = {{"s", 1000.0}, {"u", -3.0}};
  EXPECT_EQ(*encode_can_message(m, big), (std::vector<uint8_t>{0x7F, 0x00}));
  const std::vector<CanSignalInput> small = {{"s", -1000.0}, {"u", 99.0}};
  EXPECT_EQ(*encode_can_message(m, small), (std::vector<uint8_t>{0x80, 0x0F}));
  const std::vector<CanSignalInput> unknown = {{"nope", 1.0}};
  EXPECT_FALSE(encode_can_message(m, unknown).has_value());
}

CanMessageSpec dvl_like() {
  CanMessageSpec m{"dvl", 0x200, false, 8, "", {}, "", ""};
  CanSignalSpec vx = sig("v_x_mps", 0, 16, kIntel, true, 1.0, 0.0, "mm/s");
  vx.invalid_raw = 0x8000;
  vx.min = -5000.0;
  vx.max = 5000.0;
  CanSignalSpec t = sig("time_s", 16, 32, kIntel, false, 1.0, 0.0, "ms");
  t.time_of_validity = true;
  m.signals = {vx, t};
  return m;
}

TEST(CanSignals, InvalidPatternAndRangeGiveEmptyValuesAndCounters) {
  CanSignalDecoder decoder({dvl_like()});
  const Timestamps host{HostTime{5'000'000, 1'700'000'000'000'000}, std::nullopt};
  std::vector<uint8_t> f = {0x00, 0x80, 0x10, 0x27, 0, 0, 0, 0};  // vx invalid, t = 10000 ms
  auto msg = decoder.decode(0x200, false, f, host);
  ASSERT_TRUE(msg);
  EXPECT_FALSE(msg->value("v_x_mps").has_value());
  ASSERT_TRUE(msg->time.sensor_time_us.has_value());
  EXPECT_EQ(*msg->time.sensor_time_us, 10'000'000);
  EXPECT_EQ(msg->time.host.monotonic_us, 5'000'000);
  EXPECT_EQ(decoder.stats().out_of_range, 0u);

  f[0] = 0x89;  // 0x1389 = 5001 mm/s > max
  f[1] = 0x13;
  msg = decoder.decode(0x200, false, f, host);
  ASSERT_TRUE(msg);
  EXPECT_FALSE(msg->value("v_x_mps").has_value());
  EXPECT_TRUE(msg->signals[0].out_of_range);
  EXPECT_EQ(decoder.stats().out_of_range, 1u);

  f[0] = 0x88;  // 5000 mm/s: at the bound, accepted, converted to m/s
  msg = decoder.decode(0x200, false, f, host);
  EXPECT_DOUBLE_EQ(*msg->value("v_x_mps"), 5.0);
  EXPECT_EQ(decoder.stats().records, 3u);
  EXPECT_EQ(decoder.stats().bytes, 24u);
}

TEST(CanSignals, UnknownIdsAndWrongLengthsAreCountedNotDecoded) {
  CanSignalDecoder decoder({dvl_like()});
  const std::vector<uint8_t> eight(8, 0);
  const std::vector<uint8_t> seven(7, 0);
  EXPECT_FALSE(decoder.decode(0x201, false, eight, {}));
  EXPECT_FALSE(decoder.decode(0x200, true, eight, {}));  // same number, extended: unknown
  EXPECT_FALSE(decoder.decode(0x200, false, seven, {}));
  EXPECT_TRUE(decoder.decode(0x200, false, eight, {}));
  const DecodeStats& s = decoder.stats();
  EXPECT_EQ(s.unsupported, 2u);
  EXPECT_EQ(s.malformed, 1u);
  EXPECT_EQ(s.records, 1u);
  EXPECT_EQ(s.bytes, 31u);
  EXPECT_EQ(s.dropped_bytes, 23u);
}

TEST(CanSignals, MultiplexedSignalsFollowTheSwitch) {
  CanMessageSpec m{"range", 0x202, false, 4, "beam", {}, "", ""};
  CanSignalSpec r1 = sig("r1_m", 8, 16, kIntel, false, 1.0, 0.0, "mm");
  r1.multiplexer_value = 0;
  CanSignalSpec r2 = sig("r2_m", 8, 16, kIntel, false, 1.0, 0.0, "mm");
  r2.multiplexer_value = 1;
  m.signals = {sig("beam", 0, 8, kIntel), r1, r2, sig("q", 24, 8, kIntel)};
  CanSignalDecoder decoder({m});
  const std::vector<CanSignalInput> in = {{"beam", 1.0}, {"r2_m", 12.345}, {"q", 7.0}};
  const auto bytes = encode_can_message(m, in);
  ASSERT_TRUE(bytes);
  EXPECT_EQ(*bytes, (std::vector<uint8_t>{0x01, 0x39, 0x30, 0x07}));  // 12345 = 0x3039
  const auto out = decoder.decode(0x202, false, *bytes, {});
  ASSERT_TRUE(out);
  EXPECT_EQ(out->multiplexer_value, 1u);
  EXPECT_EQ(out->signals.size(), 3u);  // beam, r2, q
  EXPECT_FALSE(out->value("r1_m").has_value());
  EXPECT_DOUBLE_EQ(*out->value("r2_m"), 12.345);
  EXPECT_EQ(*out->value("q"), 7.0);
}

std::vector<CanMessageSpec> linked_pair() {
  CanMessageSpec time{"time", 0x201, false, 5, "", {}, "", ""};
  CanSignalSpec t = sig("time_s", 0, 32, kIntel, false, 1.0, 0.0, "ms");
  t.time_of_validity = true;
  time.signals = {t, sig("seq", 32, 8, kIntel)};
  CanMessageSpec vel{"vel", 0x200, false, 3, "", {}, "time", "seq"};
  vel.signals = {sig("v_mps", 0, 16, kIntel, true, 1.0, 0.0, "mm/s"), sig("seq", 16, 8, kIntel)};
  return {time, vel};
}

TEST(CanSignals, TimeLinkDatesMessagesWithoutTheirOwnCounter) {
  CanSignalDecoder decoder(linked_pair());
  const CanMessageSpec& time = *decoder.find("time");
  const CanMessageSpec& vel = *decoder.find("vel");
  auto time_frame = [&](double t_s, int seq) {
    const std::vector<CanSignalInput> in = {{"time_s", t_s}, {"seq", double(seq)}};
    return *encode_can_message(time, in);
  };
  auto vel_sensor_time = [&](int seq) {
    const std::vector<CanSignalInput> in = {{"v_mps", 0.5}, {"seq", double(seq)}};
    return decoder.decode(0x200, false, *encode_can_message(vel, in), {})->time.sensor_time_us;
  };
  EXPECT_FALSE(vel_sensor_time(5).has_value());  // no time message yet
  ASSERT_TRUE(decoder.decode(0x201, false, time_frame(1.0, 5), {}));
  EXPECT_EQ(vel_sensor_time(5), 1'000'000);
  EXPECT_FALSE(vel_sensor_time(6).has_value());
  for (int seq = 6; seq <= 10; ++seq) decoder.decode(0x201, false, time_frame(seq, seq), {});
  EXPECT_EQ(vel_sensor_time(10), 10'000'000);
  EXPECT_EQ(vel_sensor_time(7), 7'000'000);      // the last four are remembered
  EXPECT_FALSE(vel_sensor_time(5).has_value());  // pushed out
  ASSERT_TRUE(decoder.decode(0x201, false, time_frame(11.0, 7), {}));  // seq wrapped around
  EXPECT_EQ(vel_sensor_time(7), 11'000'000);                           // the newest wins
}

TEST(CanSignals, TimeLinkValidation) {
  auto error_of = [](void (*edit)(std::vector<CanMessageSpec>&)) {
    std::vector<CanMessageSpec> ms = linked_pair();
    edit(ms);
    return validate_can_messages(ms);
  };
  EXPECT_EQ(error_of([](auto&) {}), "");
  EXPECT_EQ(error_of([](auto& ms) { ms[1].time_from = "nope"; }),
            "messages[1].time_from: \"nope\" is not another message of the table");
  EXPECT_EQ(error_of([](auto& ms) { ms[1].time_match = ""; }),
            "messages[1].time_match: time_from and time_match go together");
  EXPECT_EQ(error_of([](auto& ms) { ms[0].signals[1].name = "sequence"; }),
            "messages[1].time_match: \"seq\" is not an unmultiplexed signal of message \"time\"");
  EXPECT_EQ(error_of([](auto& ms) { ms[0].signals[0].time_of_validity = false; }),
            "messages[1].time_from: message \"time\" has no time_of_validity signal");
  EXPECT_EQ(error_of([](auto& ms) { ms[1].time_from = "vel"; }),
            "messages[1].time_from: \"vel\" is not another message of the table");
}

TEST(CanSignals, UnitsConvertToSi) {
  EXPECT_DOUBLE_EQ(can_unit_to_si("deg")->factor, std::numbers::pi / 180.0);
  EXPECT_EQ(can_unit_to_si("deg/s")->si_unit, "rad/s");
  EXPECT_DOUBLE_EQ(can_unit_to_si("cm/s")->factor, 0.01);
  EXPECT_DOUBLE_EQ(can_unit_to_si("dbar")->factor, 1e4);
  EXPECT_FALSE(can_unit_to_si("furlong").has_value());
}

TEST(CanSignals, TimeCounterModulus) {
  CanSignalSpec ms = sig("t", 0, 16, kIntel, false, 1.0, 0.0, "ms");
  EXPECT_EQ(can_time_signal_modulus_us(ms), 65'536'000);
  CanSignalSpec us = sig("t", 0, 32, kIntel, false, 1.0, 0.0, "us");
  EXPECT_EQ(can_time_signal_modulus_us(us), int64_t{1} << 32);
  EXPECT_FALSE(can_time_signal_modulus_us(sig("x", 0, 8, kIntel, false, 1.0, 0.0, "m")));
  EXPECT_FALSE(can_time_signal_modulus_us(sig("x", 0, 8, kIntel, true, 1.0, 0.0, "ms")));
  EXPECT_EQ(can_time_signal_resolution_us(ms), 1000);
  EXPECT_EQ(can_time_signal_resolution_us(sig("t", 0, 8, kIntel, false, 0.1, 0.0, "s")), 100'000);
  EXPECT_EQ(can_time_signal_resolution_us(sig("x", 0, 8, kIntel, false, 1.0, 0.0, "m")), 0);
}

TEST(CanSignals, ValidationNamesThePathAndReason) {
  CanMessageSpec ok = dvl_like();
  EXPECT_EQ(validate_can_messages({ok}), "");
  auto error_of = [](std::vector<CanMessageSpec> ms) { return validate_can_messages(ms); };

  CanMessageSpec a = ok;
  a.signals[1].length = 0;
  EXPECT_EQ(error_of({ok, ok, a}).rfind("messages[1].name", 0), 0u);  // duplicate name first
  CanMessageSpec b = ok;
  b.name = "other";
  b.id = 0x300;
  b.signals[0].length = 0;
  EXPECT_EQ(error_of({ok, b}), "messages[1].signals[0].length: 0 is not in 1..64");

  CanMessageSpec c = ok;
  c.dlc = 4;
  EXPECT_EQ(error_of({c}), "messages[0].signals[1]: needs 6 data bytes but the message dlc is 4");
  CanMessageSpec d = ok;
  d.id = 0x800;
  EXPECT_NE(error_of({d}).find("messages[0].id: 0x800 does not fit in 11 bits"), std::string::npos);
  CanMessageSpec e = ok;
  e.signals[0].unit = "knots";
  EXPECT_EQ(error_of({e}), "messages[0].signals[0].unit: unknown unit \"knots\"");
  CanMessageSpec f = ok;
  f.signals[0].start_bit = 3;
  f.signals[0].byte_order = kMotorola;
  f.signals[0].start_bit = 60;  // 16 bits from Motorola bit 60 run past byte 7
  EXPECT_NE(error_of({f}).find("run past the end"), std::string::npos);
  CanMessageSpec g = ok;
  g.signals[0].invalid_raw = 0x10000;
  EXPECT_NE(error_of({g}).find("signals[0].invalid"), std::string::npos);
  CanMessageSpec h = ok;
  h.signals[0].time_of_validity = true;
  EXPECT_NE(error_of({h}).find("not a time unit"), std::string::npos);
  CanMessageSpec i = ok;
  i.multiplexer = "missing";
  EXPECT_EQ(error_of({i}), "messages[0].multiplexer: \"missing\" is not a signal of the message");
  EXPECT_THROW(CanSignalDecoder({i}), std::invalid_argument);
}

TEST(CanSignals, RandomFramesNeverCrashAndAreAllCounted) {
  CanSignalDecoder decoder({motohawk(), dvl_like()});
  std::mt19937_64 rng(3);
  CanDecodedMessage out;
  uint64_t bytes = 0;
  for (int i = 0; i < 5000; ++i) {
    std::vector<uint8_t> data(rng() % 9);
    for (auto& b : data) b = static_cast<uint8_t>(rng());
    bytes += data.size();
    const uint32_t id = (rng() % 2) ? 496 : static_cast<uint32_t>(0x1F0 + rng() % 32);
    decoder.decode(id, false, data, {}, out);
  }
  const DecodeStats& s = decoder.stats();
  EXPECT_EQ(s.bytes, bytes);
  EXPECT_EQ(s.records + s.unsupported + s.malformed, 5000u);
  EXPECT_GT(s.records, 0u);
}

}  // namespace
}  // namespace nav::drivers
