// CAN config loader: the shipped DVL + FOG example loads and its messages round-trip through
// the encoder and decoder; errors name the file, key path and reason.

#include "nav/drivers/config/can_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>

namespace nav::drivers {
namespace {

const std::string kExample =
    (std::filesystem::path(NAV_SOURCE_DIR) / "config/can/dvl_fog_example.yaml")
        .lexically_normal()
        .string();

constexpr double kDeg = std::numbers::pi / 180.0;

/// Loads `yaml` and returns the error message (empty when it loads).
std::string error_of(const std::string& yaml) {
  try {
    parse_can_config(yaml, "t.yaml");
  } catch (const CanConfigError& e) {
    return e.what();
  }
  return {};
}

const std::string kMinimal = R"(
messages:
  - name: m
    id: 0x123
    dlc: 2
    signals:
      - {name: a, start_bit: 0, length: 16, byte_order: intel}
)";

TEST(CanConfig, ExampleLoadsWithTheDocumentedLayout) {
  const CanConfig config = load_can_config_file(kExample);
  ASSERT_EQ(config.messages.size(), 6u);
  CanSignalDecoder decoder(config.messages);
  const CanMessageSpec* fog = decoder.find(0x18FF1002, true);
  ASSERT_NE(fog, nullptr);
  EXPECT_EQ(fog->name, "fog_rates");
  EXPECT_EQ(fog->signals[1].start_bit, 19u);
  EXPECT_EQ(fog->signals[1].byte_order, CanByteOrder::kMotorola);
  const CanMessageSpec* velocity = decoder.find("dvl_velocity");
  ASSERT_NE(velocity, nullptr);
  EXPECT_EQ(velocity->id, 0x200u);
  EXPECT_EQ(velocity->signals[0].invalid_raw, 0x8000u);  // "invalid: -32768" of 16 bits
  EXPECT_EQ(decoder.find("dvl_range")->multiplexer, "beam_index");
  // The DVL time counter is 32-bit milliseconds: it wraps after 2^32 ms.
  const CanSignalSpec& t = decoder.find("dvl_time")->signals[0];
  EXPECT_TRUE(t.time_of_validity);
  EXPECT_EQ(can_time_signal_modulus_us(t), (int64_t{1} << 32) * 1000);
}

TEST(CanConfig, ExampleFramesRoundTrip) {
  CanSignalDecoder decoder(load_can_config_file(kExample).messages);
  struct Case {
    std::string message;
    std::vector<CanSignalInput> values;
    double tolerance;
  };
  const std::vector<Case> cases = {
      {"dvl_velocity",
       {{"v_x_mps", 1.2345},
        {"v_y_mps", -0.4321},
        {"v_z_mps", 0.0123},
        {"bottom_track_valid", 1},
        {"water_track_valid", 0},
        {"beams_used", 4},
        {"error_flag", 0},
        {"ping_seq", 201}},
       0.5e-4},
      {"dvl_time",
       {{"time_s", 4'000'000.125},
        {"ping_seq", 201},
        {"altitude_m", 12.34},
        {"temperature_degC", -1.5}},
       0.5e-3},
      {"dvl_range",
       {{"beam_index", 2}, {"range_beam3_m", 45.678}, {"ping_seq", 9}, {"beam_quality", 200}},
       0.5e-3},
      {"fog_attitude",
       {{"heading_rad", 359.99 * kDeg},
        {"roll_rad", -12.34 * kDeg},
        {"pitch_rad", 5.67 * kDeg},
        {"fog_ok", 1},
        {"aligned", 1},
        {"mode", 5},
        {"seq", 77}},
       0.005 * kDeg},
      {"fog_rates",
       {{"rate_x_radps", -49.9999 * kDeg},
        {"rate_y_radps", 0.0001 * kDeg},
        {"rate_z_radps", 12.3456 * kDeg},
        {"rate_status", 9}},
       0.00005 * kDeg},
      {"fog_time", {{"time_s", 4000.000123}, {"seq", 78}}, 0.5e-6},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.message);
    const CanMessageSpec* spec = decoder.find(c.message);
    ASSERT_NE(spec, nullptr);
    const auto bytes = encode_can_message(*spec, c.values);
    ASSERT_TRUE(bytes.has_value());
    ASSERT_EQ(bytes->size(), spec->dlc);
    const auto decoded = decoder.decode(spec->id, spec->extended, *bytes, {});
    ASSERT_TRUE(decoded.has_value());
    for (const CanSignalInput& in : c.values) {
      const auto v = decoded->value(in.name);
      ASSERT_TRUE(v.has_value()) << in.name;
      EXPECT_NEAR(*v, in.value_si, c.tolerance) << in.name;
    }
  }
  EXPECT_EQ(decoder.stats().records, cases.size());
  EXPECT_EQ(decoder.stats().out_of_range, 0u);
}

TEST(CanConfig, ExampleTimeSignalsGiveSensorTimes) {
  CanSignalDecoder decoder(load_can_config_file(kExample).messages);
  const CanMessageSpec& fog_time = *decoder.find("fog_time");
  const std::vector<CanSignalInput> in = {{"time_s", 1234.567891}};
  const auto decoded = decoder.decode(fog_time.id, true, *encode_can_message(fog_time, in), {});
  ASSERT_TRUE(decoded && decoded->time.sensor_time_us);
  EXPECT_EQ(*decoded->time.sensor_time_us, 1'234'567'891);
  // An invalid (missing) value leaves the DVL velocity empty, not zero.
  const CanMessageSpec& vel = *decoder.find("dvl_velocity");
  const std::vector<CanSignalInput> partial = {{"v_x_mps", 0.5}};
  const auto v = decoder.decode(vel.id, false, *encode_can_message(vel, partial), {});
  EXPECT_DOUBLE_EQ(*v->value("v_x_mps"), 0.5);
  EXPECT_FALSE(v->value("v_y_mps").has_value());
}

TEST(CanConfig, EveryFlippedBitChangesOnlyTheSignalThatOwnsIt) {
  // The example's layouts do not overlap (apart from multiplexed alternatives): flipping one
  // payload bit changes the raw value of exactly the signal that covers it, by one bit.
  CanSignalDecoder decoder(load_can_config_file(kExample).messages);
  size_t owned_bits = 0;
  for (const CanMessageSpec& spec : decoder.messages()) {
    const std::vector<uint8_t> zero(spec.dlc, 0);
    const auto base = decoder.decode(spec.id, spec.extended, zero, {});
    ASSERT_TRUE(base.has_value());
    for (uint32_t bit = 0; bit < 8u * spec.dlc; ++bit) {
      std::vector<uint8_t> flipped = zero;
      flipped[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
      const auto f = decoder.decode(spec.id, spec.extended, flipped, {});
      ASSERT_TRUE(f.has_value());
      if (f->multiplexer_value != base->multiplexer_value) continue;  // the switch itself
      size_t changed = 0;
      for (size_t i = 0; i < f->signals.size(); ++i) {
        const uint64_t diff = f->signals[i].raw ^ base->signals[i].raw;
        if (diff == 0) continue;
        ++changed;
        EXPECT_EQ(diff & (diff - 1), 0u) << spec.name << " bit " << bit;  // a single bit
      }
      EXPECT_LE(changed, 1u) << spec.name << " bit " << bit;
      owned_bits += changed;
    }
  }
  // Bits covered by the example's signals: dvl_velocity 62 (bits 54, 55 spare), dvl_time 64,
  // dvl_range 40 (beam 1's range, ping_seq, quality; the switch byte is skipped),
  // fog_attitude 61 (bits 48..50 spare), fog_rates 64, fog_time 40.
  EXPECT_EQ(owned_bits, 62u + 64u + 40u + 61u + 64u + 40u);
}

TEST(CanConfig, MinimalConfigWithHexAndDefaults) {
  const CanConfig c = parse_can_config(kMinimal);
  ASSERT_EQ(c.messages.size(), 1u);
  EXPECT_EQ(c.messages[0].id, 0x123u);
  EXPECT_FALSE(c.messages[0].extended);
  EXPECT_EQ(c.messages[0].signals[0].scale, 1.0);
  EXPECT_FALSE(c.messages[0].signals[0].is_signed);
  EXPECT_FALSE(c.messages[0].signals[0].min.has_value());
  // DBC's [0|0] means "no range", not "only zero".
  std::string dbc_style = kMinimal;
  dbc_style.replace(dbc_style.find("intel}"), 6, "intel, min: 0, max: 0}");
  const CanConfig d = parse_can_config(dbc_style);
  EXPECT_FALSE(d.messages[0].signals[0].min.has_value());
  EXPECT_FALSE(d.messages[0].signals[0].max.has_value());
  std::string ranged = kMinimal;
  ranged.replace(ranged.find("intel}"), 6, "intel, min: 0, max: 10}");
  EXPECT_EQ(parse_can_config(ranged).messages[0].signals[0].max, 10.0);
}

TEST(CanConfig, ErrorsNameFileKeyPathAndReason) {
  auto with = [](const std::string& from, const std::string& to) {
    std::string y = kMinimal;
    y.replace(y.find(from), from.size(), to);
    return y;
  };
  EXPECT_EQ(error_of(with("length: 16", "length: 0")),
            "t.yaml: messages[0].signals[0].length: 0 is not in 1..64");
  EXPECT_EQ(error_of(with("length: 16", "lenght: 16")),
            "t.yaml: messages[0].signals[0].lenght: unknown key");
  EXPECT_EQ(error_of(with("id: 0x123", "id: 0x12G")),
            "t.yaml: messages[0].id: \"0x12G\" is not an integer");
  EXPECT_EQ(error_of(with("    id: 0x123\n", "")), "t.yaml: messages[0].id: missing");
  EXPECT_EQ(error_of(with("intel", "middle")),
            "t.yaml: messages[0].signals[0].byte_order: \"middle\" is not one of intel, "
            "little_endian, motorola, big_endian");
  EXPECT_EQ(error_of(with("dlc: 2", "dlc: 1")),
            "t.yaml: messages[0].signals[0]: needs 2 data bytes but the message dlc is 1");
  EXPECT_EQ(error_of(with("dlc: 2", "dlc: 9")), "t.yaml: messages[0].dlc: 9 is not in 0..8");
  EXPECT_EQ(error_of(with("byte_order: intel", "byte_order: intel, invalid: -1")),
            "t.yaml: messages[0].signals[0].invalid: negative for an unsigned signal");
  EXPECT_EQ(error_of(with("byte_order: intel", "byte_order: intel, scale: fast")),
            "t.yaml: messages[0].signals[0].scale: \"fast\" is not a number");
  EXPECT_EQ(error_of("messages: {a: 1}"), "t.yaml: messages: must be a list");
  EXPECT_EQ(error_of("mesages: []"), "t.yaml: (top level).mesages: unknown key");
  const std::string syntax = error_of("messages:\n  - name: [unclosed\n");
  EXPECT_EQ(syntax.rfind("t.yaml: YAML syntax error at line ", 0), 0u) << syntax;
  try {
    load_can_config_file("/nonexistent/can.yaml");
    FAIL() << "no error for a missing file";
  } catch (const CanConfigError& e) {
    EXPECT_STREQ(e.what(), "/nonexistent/can.yaml: cannot open the CAN config file");
  }
}

}  // namespace
}  // namespace nav::drivers
