// KVH DSP-3000 ASCII codec: the three output modes, status flag, units, resynchronisation on
// line breaks, garbage, range checks, chunking independence and encoder round trips.
#include "nav/drivers/codecs/kvh.h"

#include <gtest/gtest.h>

#include <numbers>
#include <string>
#include <vector>

#include "ascii_decode_support.h"

namespace nav::drivers {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
const HostTime kHost{5, 6};

using Result = test::DecodeResult<KvhRecord>;

Result decode(const std::string& text, KvhOptions options = {}) {
  return test::decode_text<KvhDecoder, KvhRecord>(text, options, kHost);
}

std::string describe(const std::vector<KvhRecord>& records, const KvhOptions& options = {}) {
  std::string text;
  for (const auto& r : records) text += encode_kvh(r, options);
  return text;
}

TEST(Kvh, RateLinesWithStatus) {
  const Result r = decode("   0.0123456   1\r\n  -12.5000000   1\r\n   3.0000000   0\r\n");
  ASSERT_EQ(r.records.size(), 3u);
  ASSERT_TRUE(r.records[0].rate_radps.has_value());
  EXPECT_NEAR(*r.records[0].rate_radps, 0.0123456 * kDeg, 1e-15);
  EXPECT_NEAR(*r.records[1].rate_radps, -12.5 * kDeg, 1e-15);
  EXPECT_TRUE(r.records[0].sensor_valid);
  // Status '0': the sample is reported, its value is not.
  EXPECT_FALSE(r.records[2].sensor_valid);
  EXPECT_FALSE(r.records[2].rate_radps.has_value());
  EXPECT_FALSE(r.records[0].angle_rad.has_value());
  EXPECT_EQ(r.records[0].time.host.realtime_us, 6);
  EXPECT_EQ(r.stats.dropped_bytes, 0u);
}

TEST(Kvh, AngleModesAndRadianUnit) {
  KvhOptions incremental;
  incremental.mode = KvhOutputMode::kIncrementalAngle;
  const Result a = decode("0.0500000 1\n", incremental);
  ASSERT_EQ(a.records.size(), 1u);
  EXPECT_NEAR(*a.records[0].angle_rad, 0.05 * kDeg, 1e-15);
  EXPECT_FALSE(a.records[0].rate_radps.has_value());

  KvhOptions integrated;
  integrated.mode = KvhOutputMode::kIntegratedAngle;
  integrated.unit = KvhAngleUnit::kRadians;
  const Result b = decode("1234.5 1\r", integrated);
  ASSERT_EQ(b.records.size(), 1u);
  EXPECT_DOUBLE_EQ(*b.records[0].angle_rad, 1234.5);  // beyond the rate limit, fine for P mode
}

TEST(Kvh, AbsurdRatesRejectedAndCounted) {
  const Result r = decode("400.0 1\r\n-376.0 1\r\n374.0 1\r\n");
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_EQ(r.stats.out_of_range, 2u);
  KvhOptions integrated;
  integrated.mode = KvhOutputMode::kIntegratedAngle;
  integrated.max_integrated_angle_rad = 10.0;
  EXPECT_EQ(decode("1000.0 1\n", integrated).stats.out_of_range, 1u);
}

TEST(Kvh, MalformedLinesAndGarbage) {
  const std::string good = "   0.0123456   1\r\n";
  const Result r = decode("abc 1\r\n1.0 2\r\n1.0\r\n1.0 1 1\r\nnan 1\r\n" +
                          std::string("\x00\xff\x10", 3) + good + "0.5 1" + "\x03" + good);
  ASSERT_EQ(r.records.size(), 2u);
  EXPECT_EQ(r.stats.malformed, 6u);
  EXPECT_EQ(r.stats.bytes, 2 * good.size() + r.stats.dropped_bytes);
}

TEST(Kvh, OverlongLineDroppedThenResync) {
  const std::string good = "1.0 1\r\n";
  const Result r = decode(std::string(500, '1') + "\r\n" + good);
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_EQ(r.stats.malformed, 1u);
  EXPECT_EQ(r.stats.dropped_bytes, 502u);
}

TEST(Kvh, SplitAtEveryByteGivesIdenticalOutput) {
  const std::string text = std::string("\x01\x02") + "  0.0100000   1\r\n-1.2 1\r\n\r\n" +
                           "999.0 1\r\nbad line\n 2.0000000   0\r\n" + std::string(60, '7') + "\n" +
                           "0.3 1";  // last line unterminated: stays pending
  const Result whole = decode(text);
  EXPECT_EQ(whole.records.size(), 3u);
  for (std::size_t split = 0; split <= text.size(); ++split) {
    KvhDecoder decoder;
    std::vector<KvhRecord> records;
    const auto* data = reinterpret_cast<const uint8_t*>(text.data());
    decoder.feed({data, split}, kHost, records);
    decoder.feed({data + split, text.size() - split}, kHost, records);
    ASSERT_EQ(describe(records), describe(whole.records)) << "split at " << split;
    ASSERT_EQ(decoder.stats().to_json(), whole.stats.to_json()) << "split at " << split;
  }
}

TEST(Kvh, EncoderRoundTrip) {
  for (const auto mode :
       {KvhOutputMode::kRate, KvhOutputMode::kIncrementalAngle, KvhOutputMode::kIntegratedAngle}) {
    KvhOptions options;
    options.mode = mode;
    KvhRecord valid;
    valid.mode = mode;
    valid.sensor_valid = true;
    (mode == KvhOutputMode::kRate ? valid.rate_radps : valid.angle_rad) = -0.123456 * kDeg;
    KvhRecord invalid;
    invalid.mode = mode;
    const std::string text = encode_kvh(valid, options) + encode_kvh(invalid, options);
    const Result r = decode(text, options);
    ASSERT_EQ(r.records.size(), 2u);
    EXPECT_EQ(describe(r.records, options), text);
    EXPECT_EQ(r.records[0].mode, mode);
  }
  EXPECT_EQ(encode_kvh(KvhRecord{{}, KvhOutputMode::kRate, true, 1.0 * kDeg, {}}),
            "    1.0000000   1\r\n");
}

TEST(Kvh, OptionsValidate) {
  EXPECT_EQ(KvhOptions{}.validate(), "");
  KvhOptions bad;
  bad.max_line_chars = 2;
  EXPECT_NE(bad.validate().find("max_line_chars"), std::string::npos);
  bad = KvhOptions{};
  bad.max_rate_radps = 0.0;
  EXPECT_NE(bad.validate().find("max_rate_radps"), std::string::npos);
}

}  // namespace
}  // namespace nav::drivers
