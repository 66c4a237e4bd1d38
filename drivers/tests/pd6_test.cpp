// Tests of the RDI PD6 ASCII codec: each line type from hand-written lines in the manual's
// layout, status flags and -32768 markers, range checks, framing errors, every-byte splits,
// and the encoder round trip.
#include "nav/drivers/codecs/pd6.h"

#include <gtest/gtest.h>

#include <numbers>
#include <string>
#include <vector>

namespace nav::drivers {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
const HostTime kHost{5, 6};

// One ensemble in the manual's PD6 layout (padded fields as the instrument writes them).
const std::string kEnsemble =
    ":SA, -2.31, +1.07,271.45\r\n"
    ":TS,17052412025390,35.0,+21.5,  12.3,1524.5,  0\r\n"
    ":WI,-32768,-32768,-32768,-32768,V\r\n"
    ":BI,  +120,  -340,   +50,    -1,A\r\n"
    ":WS,-32768,-32768,-32768,V\r\n"
    ":BS,  +121,  -341,   +51,A\r\n"
    ":WE,-32768,-32768,-32768,V\r\n"
    ":BE,  -100,  +200,   -30,A\r\n"
    ":WD,        +0.00,        +0.00,        +0.00,   0.00,  0.00\r\n"
    ":BD,     +1234.56,      -789.01,        -2.50,  12.34,  0.50\r\n";

std::vector<Pd6Record> decode(const std::string& text, Pd6Decoder& decoder) {
  std::vector<Pd6Record> out;
  decoder.feed({reinterpret_cast<const uint8_t*>(text.data()), text.size()}, kHost, out);
  return out;
}

TEST(Pd6Codec, DecodesEveryLineOfAnEnsemble) {
  Pd6Decoder decoder;
  const auto out = decode(kEnsemble, decoder);
  ASSERT_EQ(out.size(), 10u);
  const char* names[] = {"SA", "TS", "WI", "BI", "WS", "BS", "WE", "BE", "WD", "BD"};
  for (std::size_t i = 0; i < out.size(); ++i) EXPECT_EQ(pd6_line_name(out[i]), names[i]);

  const auto& sa = std::get<Pd6Attitude>(out[0].value);
  EXPECT_NEAR(*sa.pitch_rad, -2.31 * kDeg, 1e-12);
  EXPECT_NEAR(*sa.roll_rad, 1.07 * kDeg, 1e-12);
  EXPECT_NEAR(*sa.heading_rad, 271.45 * kDeg, 1e-12);
  EXPECT_FALSE(out[0].time.sensor_time_us);  // :SA comes before the ensemble's :TS

  const auto& ts = std::get<Pd6TimingScaling>(out[1].value);
  EXPECT_EQ(out[1].time.sensor_time_us, 1495627373'900000);  // 2017-05-24T12:02:53.90Z
  EXPECT_NEAR(*ts.salinity_ppt, 35.0, 1e-12);
  EXPECT_NEAR(*ts.temperature_c, 21.5, 1e-12);
  EXPECT_NEAR(*ts.depth_m, 12.3, 1e-12);
  EXPECT_NEAR(*ts.sound_speed_mps, 1524.5, 1e-12);
  EXPECT_EQ(ts.bit_result, 0);

  const auto& wi = std::get<Pd6Velocity>(out[2].value);
  EXPECT_FALSE(wi.valid);
  for (const auto& v : wi.velocity_mps) EXPECT_FALSE(v);

  const auto& bi = std::get<Pd6Velocity>(out[3].value);
  EXPECT_TRUE(bi.valid);
  EXPECT_EQ(bi.reference, Pd6Reference::kBottom);
  EXPECT_EQ(bi.frame, Pd6Frame::kInstrument);
  EXPECT_NEAR(*bi.velocity_mps[0], 0.120, 1e-12);
  EXPECT_NEAR(*bi.velocity_mps[1], -0.340, 1e-12);
  EXPECT_NEAR(*bi.velocity_mps[2], 0.050, 1e-12);
  EXPECT_NEAR(*bi.velocity_mps[3], -0.001, 1e-12);

  const auto& bs = std::get<Pd6Velocity>(out[5].value);
  EXPECT_EQ(bs.frame, Pd6Frame::kShip);
  EXPECT_NEAR(*bs.velocity_mps[1], -0.341, 1e-12);
  EXPECT_FALSE(bs.velocity_mps[3]);

  const auto& be = std::get<Pd6Velocity>(out[7].value);
  EXPECT_EQ(be.frame, Pd6Frame::kEarth);
  EXPECT_NEAR(*be.velocity_mps[0], -0.100, 1e-12);
  EXPECT_NEAR(*be.velocity_mps[1], 0.200, 1e-12);
  EXPECT_NEAR(*be.velocity_mps[2], -0.030, 1e-12);

  const auto& bd = std::get<Pd6Distance>(out[9].value);
  EXPECT_EQ(bd.reference, Pd6Reference::kBottom);
  EXPECT_NEAR(*bd.distance_enu_m[0], 1234.56, 1e-9);
  EXPECT_NEAR(*bd.distance_enu_m[1], -789.01, 1e-9);
  EXPECT_NEAR(*bd.distance_enu_m[2], -2.50, 1e-9);
  EXPECT_NEAR(*bd.range_m, 12.34, 1e-9);
  EXPECT_NEAR(*bd.time_since_valid_s, 0.5, 1e-9);

  // Lines after :TS carry its time; host time is the feed's.
  for (std::size_t i = 2; i < out.size(); ++i) {
    EXPECT_EQ(out[i].time.sensor_time_us, out[1].time.sensor_time_us) << i;
    EXPECT_EQ(out[i].time.host.monotonic_us, kHost.monotonic_us);
  }
  const DecodeStats& s = decoder.stats();
  EXPECT_EQ(s.records, 10u);
  EXPECT_EQ(s.bytes, kEnsemble.size());
  EXPECT_EQ(s.dropped_bytes, 0u);
  EXPECT_EQ(s.malformed + s.unsupported + s.out_of_range, 0u);
}

TEST(Pd6Codec, DecodesThirdPartyProducerExample) {
  // The example PD6 output printed in the Water Linked DVL protocol documentation ("PD6",
  // "Example output"), a PD6 producer other than RDI: zero-filled unused lines.
  const std::string text =
      ":SA, +0.00, +0.00,  0.00\r\n"
      ":TS,22020812061800, 0.0, +0.0,   0.0,1475.0,  0\r\n"
      ":WI,    +0,    +0,    +0,    +0,V\r\n"
      ":WS,    +0,    +0,    +0,V\r\n"
      ":WE,    +0,    +0,    +0,V\r\n"
      ":WD,       +0.00,       +0.00,       +0.00,   0.00,  0.00\r\n"
      ":BI,  +123,  -420, +2000,    +0,A\r\n"
      ":BS,  -420,  +123, +2000,A\r\n"
      ":BE,    +0,    +0,    +0,V\r\n"
      ":BD,       +0.00,       +0.00,       +0.00,   5.32,  0.00\r\n";
  Pd6Decoder decoder;
  const auto out = decode(text, decoder);
  ASSERT_EQ(out.size(), 10u);
  EXPECT_EQ(decoder.stats().malformed + decoder.stats().out_of_range, 0u);
  EXPECT_EQ(out[1].time.sensor_time_us, 1644321978'000000);  // 2022-02-08T12:06:18.00Z
  EXPECT_NEAR(*std::get<Pd6TimingScaling>(out[1].value).sound_speed_mps, 1475.0, 1e-12);
  const auto& bi = std::get<Pd6Velocity>(out[6].value);
  ASSERT_TRUE(bi.valid);
  EXPECT_NEAR(*bi.velocity_mps[0], 0.123, 1e-12);
  EXPECT_NEAR(*bi.velocity_mps[1], -0.420, 1e-12);
  EXPECT_NEAR(*bi.velocity_mps[2], 2.0, 1e-12);
  EXPECT_NEAR(*bi.velocity_mps[3], 0.0, 1e-12);
  EXPECT_FALSE(std::get<Pd6Velocity>(out[8].value).velocity_mps[0]);  // status V
  EXPECT_NEAR(*std::get<Pd6Distance>(out[9].value).range_m, 5.32, 1e-12);
}

TEST(Pd6Codec, NextAttitudeLineEndsTheEnsembleTime) {
  Pd6Decoder decoder;
  const auto out = decode(kEnsemble + ":SA, +0.00, +0.00,  0.00\r\n:BE,+1,+2,+3,A\r\n", decoder);
  ASSERT_EQ(out.size(), 12u);
  EXPECT_FALSE(out[10].time.sensor_time_us);
  EXPECT_FALSE(out[11].time.sensor_time_us);  // no :TS yet in this ensemble
}

TEST(Pd6Codec, RangeChecksRejectAbsurdValues) {
  const std::string lines[] = {":SA,+95.00, +1.07,271.45",
                               ":SA, -2.31, +1.07,361.00",
                               ":TS,17052412025390,35.0,+71.5,  12.3,1524.5,  0",
                               ":TS,17052412025390,35.0,+21.5,  12.3,1700.0,  0",
                               ":TS,17133212025390,35.0,+21.5,  12.3,1524.5,  0",  // month 13
                               ":BE,+25000,  +200,   -30,A",
                               ":BD,+0.00,+0.00,+0.00,2500.00,0.00"};
  for (const std::string& line : lines) {
    Pd6Decoder decoder;
    const auto out = decode(line + "\r\n", decoder);
    ASSERT_EQ(out.size(), 1u) << line;
    EXPECT_EQ(decoder.stats().out_of_range, 1u) << line;
  }
}

TEST(Pd6Codec, MalformedAndUnsupportedLinesAreDroppedAndCounted) {
  const std::string malformed[] = {":SA,+1.00,+2.00",        // missing field
                                   ":SA,+1.00,+2.00,abc",    // not a number
                                   ":SA,+1.00,+2.00,1.0.0",  // two points
                                   ":BE,+1,+2,+3,X",         // bad status flag
                                   ":BI,+1,+2,+3,A",         // instrument frame needs 4 components
                                   ":TS,1705241202539,35.0,+21.5,12.3,1524.5,0",   // 13-digit time
                                   ":TS,17052412025390,35.0,+21.5,12.3,1524.5,G",  // BIT not hex
                                   ":S",                                           // too short
                                   ":BD,+1,+2,+3,+4,+5,+6"};                       // extra field
  for (const std::string& line : malformed) {
    Pd6Decoder decoder;
    EXPECT_TRUE(decode(line + "\r\n", decoder).empty()) << line;
    EXPECT_EQ(decoder.stats().malformed, 1u) << line;
    EXPECT_EQ(decoder.stats().dropped_bytes, line.size() + 2) << line;
  }
  Pd6Decoder decoder;
  EXPECT_TRUE(decode(":RA,12.3,4\r\n", decoder).empty());
  EXPECT_EQ(decoder.stats().unsupported, 1u);
}

TEST(Pd6Decoder, GarbageOverlongAndCutLinesResynchronise) {
  const std::string overlong = ":BE," + std::string(300, '1') + "\r\n";
  const std::string good = ":BE,  -100,  +200,   -30,A\r\n";
  const std::string stream =
      "noise\r\n" + overlong + ":BE,+1,+2" /* cut by the next line */ + good + "\x01\x02";
  Pd6Decoder decoder;
  const auto out = decode(stream, decoder);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(*std::get<Pd6Velocity>(out[0].value).velocity_mps[0], -0.1, 1e-12);
  const DecodeStats& s = decoder.stats();
  EXPECT_EQ(s.malformed, 2u);  // the over-long line and the cut one
  EXPECT_EQ(s.bytes, stream.size());
  EXPECT_EQ(s.dropped_bytes + decoder.buffered_bytes() + good.size(), stream.size());
  EXPECT_LE(decoder.buffered_bytes(), Pd6Decoder::kMaxLineBytes);
}

TEST(Pd6Decoder, SplitAtEveryByteGivesIdenticalOutput) {
  const std::string stream = "xx" + kEnsemble + ":BE,+1,+2\n:ZZ,1\r\n" + kEnsemble + ":SA,+1";
  Pd6Decoder whole;
  const auto reference = decode(stream, whole);
  ASSERT_EQ(reference.size(), 20u);
  for (std::size_t k = 0; k <= stream.size(); ++k) {
    Pd6Decoder split;
    auto out = decode(stream.substr(0, k), split);
    const auto rest = decode(stream.substr(k), split);
    out.insert(out.end(), rest.begin(), rest.end());
    ASSERT_EQ(out.size(), reference.size()) << k;
    for (std::size_t i = 0; i < out.size(); ++i) {
      EXPECT_EQ(encode_pd6(out[i]), encode_pd6(reference[i])) << k;
      EXPECT_EQ(out[i].time.sensor_time_us, reference[i].time.sensor_time_us) << k;
    }
    EXPECT_EQ(split.stats().to_json(), whole.stats().to_json()) << k;
    EXPECT_EQ(split.buffered_bytes(), whole.buffered_bytes());
  }
}

TEST(Pd6Codec, EncoderRoundTripOfEveryLine) {
  Pd6Decoder decoder;
  const auto first = decode(kEnsemble, decoder);
  std::string encoded;
  for (const auto& r : first) encoded += encode_pd6(r);
  Pd6Decoder again_decoder;
  const auto again = decode(encoded, again_decoder);
  ASSERT_EQ(again.size(), first.size()) << encoded;
  EXPECT_EQ(again_decoder.stats().malformed, 0u);
  for (std::size_t i = 0; i < again.size(); ++i) {
    EXPECT_EQ(encode_pd6(again[i]), encode_pd6(first[i]));
    EXPECT_EQ(again[i].time.sensor_time_us, first[i].time.sensor_time_us);
  }
  // Fixed-width output as in the manual.
  EXPECT_EQ(encode_pd6(first[7]), ":BE,-00100,+00200,-00030,A\r\n");
  EXPECT_EQ(encode_pd6(first[1]), ":TS,17052412025390,35.0,+21.5,0012.3,1524.5,  0\r\n");

  // Empty values are written so that they decode empty again.
  Pd6Record empty_attitude{{}, Pd6Attitude{}};
  Pd6Record empty_ts{{}, Pd6TimingScaling{}};
  Pd6Decoder d;
  const auto back = decode(encode_pd6(empty_attitude) + encode_pd6(empty_ts), d);
  ASSERT_EQ(back.size(), 2u);
  const auto& a = std::get<Pd6Attitude>(back[0].value);
  EXPECT_FALSE(a.pitch_rad || a.roll_rad || a.heading_rad);
  const auto& t = std::get<Pd6TimingScaling>(back[1].value);
  EXPECT_FALSE(t.salinity_ppt || t.temperature_c || t.depth_m || t.sound_speed_mps);
  EXPECT_FALSE(back[1].time.sensor_time_us);
}

}  // namespace
}  // namespace nav::drivers
