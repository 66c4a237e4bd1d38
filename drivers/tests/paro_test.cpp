// Paroscientific Digiquartz reply codec: ids, units to pascal, commands echoed on the line,
// garbage, range checks, chunking independence and the poll reply/command encoders.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "ascii_decode_support.h"
#include "nav/drivers/codecs/paroscientific.h"

namespace nav::drivers {
namespace {

const HostTime kHost{7, 8};

using Result = test::DecodeResult<ParoRecord>;

Result decode(const std::string& text, ParoOptions options = {}) {
  return test::decode_text<ParoDecoder, ParoRecord>(text, options, kHost);
}

std::string describe(const std::vector<ParoRecord>& records) {
  std::string text;
  for (const auto& r : records) text += encode_paro_reply(r, {}, 6);
  return text;
}

TEST(Paro, PsiaReplyToPascal) {
  const Result r = decode("*000114.6959\r\n");
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_EQ(r.records[0].destination_id, 0);
  EXPECT_EQ(r.records[0].source_id, 1);
  // 14.6959 psi = 1 standard atmosphere (101325 Pa) to 5 digits.
  EXPECT_NEAR(r.records[0].pressure_pa, 101325.0, 1.0);
  EXPECT_EQ(r.records[0].time.host.monotonic_us, 7);
  EXPECT_EQ(r.stats.dropped_bytes, 0u);
}

TEST(Paro, UnitsMatchTheManualConversionFactors) {
  // Digiquartz manual UN table, per psi: 68.94757 hPa, 0.06894757 bar, 6.894757 kPa,
  // 0.006894757 MPa, 2.036021 inHg, 51.71493 mmHg, 0.7030696 mH2O.
  const struct {
    ParoPressureUnit unit;
    double per_psi;
  } cases[] = {{ParoPressureUnit::kHpa, 68.94757},   {ParoPressureUnit::kBar, 0.06894757},
               {ParoPressureUnit::kKpa, 6.894757},   {ParoPressureUnit::kMpa, 0.006894757},
               {ParoPressureUnit::kInHg, 2.036021},  {ParoPressureUnit::kMmHg, 51.71493},
               {ParoPressureUnit::kMH2O, 0.7030696}, {ParoPressureUnit::kDbar, 0.6894757}};
  const double pa_per_psi = pascal_per_unit(ParoPressureUnit::kPsi);
  for (const auto& c : cases) {
    EXPECT_NEAR(pascal_per_unit(c.unit) * c.per_psi / pa_per_psi, 1.0, 2e-6)
        << static_cast<int>(c.unit);
  }
  ParoOptions dbar;
  dbar.unit = ParoPressureUnit::kDbar;
  const Result r = decode("*00011000.0000\r\n", dbar);
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_DOUBLE_EQ(r.records[0].pressure_pa, 1.0e7);
  ParoOptions custom;
  custom.unit = ParoPressureUnit::kCustom;
  custom.custom_pa_per_unit = 2.5;
  EXPECT_DOUBLE_EQ(decode("*00012.0\r\n", custom).records.at(0).pressure_pa, 5.0);
}

TEST(Paro, CommandsAndTextRepliesAreUnsupported) {
  const Result r = decode(encode_paro_command(1, "P3") + "*0001UN=1\r\n" + "*000114.7\r\n");
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_EQ(r.stats.unsupported, 2u);
  EXPECT_EQ(encode_paro_command(1, "P4"), "*0100P4\r\n");
}

TEST(Paro, SourceIdFilter) {
  ParoOptions options;
  options.source_id = 2;
  const Result r = decode("*000114.7\r\n*000214.8\r\n", options);
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_EQ(r.records[0].source_id, 2);
  EXPECT_EQ(r.stats.unsupported, 1u);
}

TEST(Paro, MalformedGarbageAndRanges) {
  const std::string good = "*000114.7\r\n";
  const Result r =
      decode("0001 14.7\r\n*0A0114.7\r\n*0001\r\n*000114.7.2\r\n*0001-nan\r\n" +
             std::string("\xff\x00", 2) + good + "*000150000.0\r\n" + "*0001-20.0\r\n" + good);
  ASSERT_EQ(r.records.size(), 2u);
  EXPECT_EQ(r.stats.malformed, 5u);
  EXPECT_EQ(r.stats.out_of_range, 2u);  // 50 kpsi > 276 MPa; -20 psi impossible
  EXPECT_EQ(r.stats.bytes, 2 * good.size() + r.stats.dropped_bytes);
}

TEST(Paro, SplitAtEveryByteGivesIdenticalOutput) {
  const std::string text = std::string("\x13\x11") + "*000114.6959\r\n  *000214.7000\r\n" +
                           "*0100P4\r\n*0001garbage\r\n*000199999999\r\n\n*0001 1.5\r\n*00";
  const Result whole = decode(text);
  EXPECT_EQ(whole.records.size(), 3u);
  for (std::size_t split = 0; split <= text.size(); ++split) {
    ParoDecoder decoder;
    std::vector<ParoRecord> records;
    const auto* data = reinterpret_cast<const uint8_t*>(text.data());
    decoder.feed({data, split}, kHost, records);
    decoder.feed({data + split, text.size() - split}, kHost, records);
    ASSERT_EQ(describe(records), describe(whole.records)) << "split at " << split;
    ASSERT_EQ(decoder.stats().to_json(), whole.stats.to_json()) << "split at " << split;
  }
}

TEST(Paro, EncoderRoundTrip) {
  const ParoRecord record{{}, 0, 3, 2.5e6};
  for (const auto unit : {ParoPressureUnit::kPsi, ParoPressureUnit::kKpa, ParoPressureUnit::kBar,
                          ParoPressureUnit::kDbar, ParoPressureUnit::kMH2O}) {
    ParoOptions options;
    options.unit = unit;
    const std::string text = encode_paro_reply(record, options, 6);
    const Result r = decode(text, options);
    ASSERT_EQ(r.records.size(), 1u) << text;
    EXPECT_EQ(r.records[0].source_id, 3);
    EXPECT_NEAR(r.records[0].pressure_pa, 2.5e6, 1e-6 * pascal_per_unit(unit) + 1e-9);
  }
  EXPECT_EQ(encode_paro_reply({{}, 0, 1, 101325.0}, {}, 4), "*000114.6959\r\n");
}

TEST(Paro, OptionsValidate) {
  EXPECT_EQ(ParoOptions{}.validate(), "");
  ParoOptions bad;
  bad.source_id = 99;
  EXPECT_NE(bad.validate().find("source_id"), std::string::npos);
  bad = ParoOptions{};
  bad.unit = ParoPressureUnit::kCustom;
  bad.custom_pa_per_unit = 0.0;
  EXPECT_NE(bad.validate().find("custom_pa_per_unit"), std::string::npos);
}

}  // namespace
}  // namespace nav::drivers
