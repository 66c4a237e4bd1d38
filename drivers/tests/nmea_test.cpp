// NMEA heading/attitude codec: public example sentences of real iXblue/SMC devices (their
// checksums check our XOR), sign conventions, framing limits, garbage, truncation, bit flips,
// range checks, chunking independence and encoder round trips.
#include "nav/drivers/codecs/nmea.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "ascii_decode_support.h"

namespace nav::drivers {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
const HostTime kHost{1000, 2000};

using Result = test::DecodeResult<NmeaRecord>;

Result decode(const std::string& text, NmeaOptions options = {}) {
  return test::decode_text<NmeaDecoder, NmeaRecord>(text, options, kHost);
}

std::string describe(const std::vector<NmeaRecord>& records) {
  std::string text;
  for (const auto& r : records) text += encode_nmea(r);
  return text;
}

void expect_same_stats(const DecodeStats& a, const DecodeStats& b) {
  EXPECT_EQ(a.to_json(), b.to_json());
}

// Sentences published with real iXblue PHINS / Octans and SMC IMU output (interface manuals and
// open-source driver tests); their checksums were computed by the instruments.
const std::vector<std::string> kIxblueSentences = {
    "$HEHDT,41.87,T*25",
    "$PIXSE,ATITUD,-0.729,-15.705*58",
    "$PIXSE,POSITI,39.27301545,14.38044597,-731.923*4D",
    "$PIXSE,SPEED_,0.972,1.082,0.412*61",
    "$HEHDT,116.581,T*25",
    "$PIXSE,ATITUD,-1.641,-0.490*6D",
    "$PIXSE,STDHRP,1.997,0.082,0.101*7C",
    "$PIXSE,STDPOS,20563.20,18004.65,50.00*7D",
    "$PIXSE,STDSPD,19.747,13.032,10.002*41",
    "$PIXSE,ALGSTS,00000045,00004000*60",
    "$PIXSE,STATUS,00000000,00000000*6F",
    "$PHTRO,0.03,M,0.15,B*59",
};
// Well-formed iXblue sentences we do not decode.
const std::vector<std::string> kUnsupported = {
    "$PIXSE,HT_STS,FFFD5551*46",
    "$PIXSE,HEAVE_,-0.211,0.031,-6.256*7E",
    "$PIXSE,TIME__,085832.738582*6B",
};

std::string join_crlf(const std::vector<std::string>& sentences) {
  std::string text;
  for (const auto& s : sentences) text += s + "\r\n";
  return text;
}

TEST(Nmea, RealSentencesChecksumsAndValues) {
  const Result r = decode(join_crlf(kIxblueSentences) + join_crlf(kUnsupported));
  EXPECT_EQ(r.stats.checksum_failures, 0u);
  EXPECT_EQ(r.stats.malformed, 0u);
  EXPECT_EQ(r.stats.unsupported, 3u);
  ASSERT_EQ(r.records.size(), kIxblueSentences.size());
  EXPECT_EQ(r.stats.records, kIxblueSentences.size());

  const auto& hdt = std::get<NmeaHeading>(r.records[0]);
  EXPECT_NEAR(hdt.heading_rad, 41.87 * kDeg, 1e-12);
  EXPECT_EQ(std::string(hdt.talker.data(), 2), "HE");
  EXPECT_EQ(hdt.time.host.monotonic_us, 1000);
  EXPECT_FALSE(hdt.time.sensor_time_us.has_value());

  // iXblue: roll positive port up (= ours), pitch positive bow down (= minus ours).
  const auto& att = std::get<NmeaAttitude>(r.records[1]);
  EXPECT_EQ(att.sentence, NmeaSentence::kIxseAtitud);
  EXPECT_NEAR(att.roll_rad, -0.729 * kDeg, 1e-12);
  EXPECT_NEAR(att.pitch_rad, 15.705 * kDeg, 1e-12);

  const auto& pos = std::get<NmeaPosition>(r.records[2]);
  EXPECT_NEAR(pos.latitude_rad, 39.27301545 * kDeg, 1e-14);
  EXPECT_NEAR(pos.longitude_rad, 14.38044597 * kDeg, 1e-14);
  ASSERT_TRUE(pos.altitude_m.has_value());
  EXPECT_DOUBLE_EQ(*pos.altitude_m, -731.923);

  // SPEED_ is east, north, up on the wire.
  const auto& vel = std::get<NmeaVelocity>(r.records[3]);
  EXPECT_DOUBLE_EQ(vel.v_ned_mps[0], 1.082);
  EXPECT_DOUBLE_EQ(vel.v_ned_mps[1], 0.972);
  EXPECT_DOUBLE_EQ(vel.v_ned_mps[2], -0.412);

  const auto& stdhrp = std::get<NmeaAttitudeStd>(r.records[6]);
  EXPECT_NEAR(stdhrp.heading_std_rad, 1.997 * kDeg, 1e-12);
  EXPECT_NEAR(stdhrp.pitch_std_rad, 0.101 * kDeg, 1e-12);
  const auto& stdpos = std::get<NmeaPositionStd>(r.records[7]);
  EXPECT_DOUBLE_EQ(stdpos.east_std_m, 18004.65);
  const auto& stdspd = std::get<NmeaVelocityStd>(r.records[8]);
  EXPECT_DOUBLE_EQ(stdspd.v_ned_std_mps[0], 13.032);
  EXPECT_DOUBLE_EQ(stdspd.v_ned_std_mps[1], 19.747);

  const auto& algsts = std::get<NmeaStatus>(r.records[9]);
  EXPECT_EQ(algsts.sentence, NmeaSentence::kIxseAlgsts);
  EXPECT_EQ(algsts.word, 0x0000400000000045ull);

  // SMC/iXblue PHTRO: 0.03 'M' = bow up 0.03 deg, 0.15 'B' = port down 0.15 deg.
  const auto& phtro = std::get<NmeaAttitude>(r.records[11]);
  EXPECT_NEAR(phtro.pitch_rad, 0.03 * kDeg, 1e-12);
  EXPECT_NEAR(phtro.roll_rad, -0.15 * kDeg, 1e-12);

  // Every byte is either in a record or counted as dropped (unsupported sentences included).
  std::size_t record_bytes = 0;
  for (const auto& s : kIxblueSentences) record_bytes += s.size() + 2;
  EXPECT_EQ(r.stats.bytes, record_bytes + r.stats.dropped_bytes);
}

TEST(Nmea, PhtroSignLetters) {
  const Result r = decode(nmea_wrap("PHTRO,2.50,P,10.00,T") + nmea_wrap("PHTRO,1.00,M,3.00,B"));
  ASSERT_EQ(r.records.size(), 2u);
  EXPECT_NEAR(std::get<NmeaAttitude>(r.records[0]).pitch_rad, -2.5 * kDeg, 1e-12);
  EXPECT_NEAR(std::get<NmeaAttitude>(r.records[0]).roll_rad, 10.0 * kDeg, 1e-12);
  EXPECT_NEAR(std::get<NmeaAttitude>(r.records[1]).pitch_rad, 1.0 * kDeg, 1e-12);
  EXPECT_NEAR(std::get<NmeaAttitude>(r.records[1]).roll_rad, -3.0 * kDeg, 1e-12);
  // Unknown sign letter or a signed magnitude is malformed.
  const Result bad = decode(nmea_wrap("PHTRO,2.50,X,1.00,T") + nmea_wrap("PHTRO,-2.50,P,1.00,T"));
  EXPECT_TRUE(bad.records.empty());
  EXPECT_EQ(bad.stats.malformed, 2u);
}

TEST(Nmea, AtitudPitchConventionIsConfigurable) {
  NmeaOptions options;
  options.ixblue_pitch_positive_bow_down = false;
  const Result r = decode(nmea_wrap("PIXSE,ATITUD,1.000,2.000"), options);
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_NEAR(std::get<NmeaAttitude>(r.records[0]).pitch_rad, 2.0 * kDeg, 1e-12);
}

TEST(Nmea, AnyTalkerHdtAndHeadingWrap) {
  const Result r = decode(nmea_wrap("GPHDT,270.0,T") + nmea_wrap("INHDT,180.0,T") +
                          nmea_wrap("PIXSE,HEADNG,359.5"));
  ASSERT_EQ(r.records.size(), 3u);
  const auto& gp = std::get<NmeaHeading>(r.records[0]);
  EXPECT_EQ(std::string(gp.talker.data(), 2), "GP");
  EXPECT_NEAR(gp.heading_rad, -90.0 * kDeg, 1e-12);
  EXPECT_NEAR(std::get<NmeaHeading>(r.records[1]).heading_rad, std::numbers::pi, 1e-12);
  EXPECT_NEAR(std::get<NmeaHeading>(r.records[2]).heading_rad, -0.5 * kDeg, 1e-12);
  EXPECT_EQ(std::get<NmeaHeading>(r.records[2]).sentence, NmeaSentence::kIxseHeadng);
}

TEST(Nmea, AbsurdValuesRejectedAndCounted) {
  const Result r = decode(
      nmea_wrap("HEHDT,400.0,T") + nmea_wrap("HEHDT,-1.0,T") + nmea_wrap("PIXSE,ATITUD,1.0,95.0") +
      nmea_wrap("PHTRO,91.00,M,1.00,T") + nmea_wrap("PIXSE,SPEED_,300.0,0.0,0.0") +
      nmea_wrap("PIXSE,POSITI,91.0,0.0,0.0") + nmea_wrap("PIXSE,STDHRP,-1.0,0.0,0.0"));
  EXPECT_TRUE(r.records.empty());
  EXPECT_EQ(r.stats.out_of_range, 7u);
  EXPECT_EQ(r.stats.dropped_bytes, r.stats.bytes);
}

TEST(Nmea, NotANumberAndEmptyFieldsAreMalformed) {
  const Result r = decode(nmea_wrap("HEHDT,nan,T") + nmea_wrap("HEHDT,inf,T") +
                          nmea_wrap("HEHDT,,T") + nmea_wrap("HEHDT,1e2,T") +
                          nmea_wrap("PIXSE,ATITUD,1.0") + nmea_wrap("PIXSE,STATUS,XYZ,0"));
  EXPECT_TRUE(r.records.empty());
  EXPECT_EQ(r.stats.malformed, 6u);
}

TEST(Nmea, TruncatedSentenceThenGoodOne) {
  const std::string truncated = "$HEHDT,41.8";
  const Result r = decode(truncated + "$HEHDT,41.87,T*25\r\n");
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_EQ(r.stats.malformed, 1u);
  EXPECT_EQ(r.stats.dropped_bytes, truncated.size());
}

TEST(Nmea, GarbageBetweenSentencesIsDroppedAndCounted) {
  const std::string good = "$HEHDT,41.87,T*25\r\n";
  const std::string garbage = std::string("\x00\xff\x7f junk \x01", 10) + "\r\n\n";
  const Result r = decode(garbage + good + garbage + good + garbage);
  ASSERT_EQ(r.records.size(), 2u);
  EXPECT_EQ(r.stats.dropped_bytes, 3 * garbage.size());
  EXPECT_EQ(r.stats.bytes, 2 * good.size() + 3 * garbage.size());
}

TEST(Nmea, BinaryByteInsideSentenceDropsIt) {
  const Result r = decode(std::string("$HEHDT,41.\x02") + "87,T*25\r\n" + "$HEHDT,41.87,T*25\r\n");
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_EQ(r.stats.malformed, 1u);
}

TEST(Nmea, EveryFlippedPayloadBitIsCaught) {
  const std::string good = "$PIXSE,ATITUD,-0.729,-15.705*58\r\n";
  const std::size_t star = good.find('*');
  for (std::size_t i = 1; i < star; ++i) {
    for (int bit = 0; bit < 7; ++bit) {
      std::string flipped = good;
      flipped[i] = static_cast<char>(flipped[i] ^ (1 << bit));
      const Result r = decode(flipped);
      EXPECT_TRUE(r.records.empty()) << "byte " << i << " bit " << bit << ": " << flipped;
      EXPECT_EQ(r.stats.dropped_bytes, r.stats.bytes);
      const char c = flipped[i];
      if (c >= 0x20 && c <= 0x7e && c != '*' && c != '$' && c != '!') {
        EXPECT_EQ(r.stats.checksum_failures, 1u) << "byte " << i << " bit " << bit;
      }
    }
  }
}

TEST(Nmea, LengthLimitsStandardAndProprietary) {
  // 82 characters including '$' and CR LF is the NMEA 0183 maximum (section 5.3).
  const std::string at_limit = nmea_wrap("GPHDT,1." + std::string(66, '0') + ",T");
  ASSERT_EQ(at_limit.size(), 82u);
  EXPECT_EQ(decode(at_limit).records.size(), 1u);
  const std::string too_long = nmea_wrap("GPHDT,1." + std::string(67, '0') + ",T");
  const Result over = decode(too_long);
  EXPECT_TRUE(over.records.empty());
  EXPECT_EQ(over.stats.malformed, 1u);
  EXPECT_EQ(over.stats.dropped_bytes, too_long.size());
  NmeaOptions options;
  options.max_proprietary_sentence_chars = 120;
  const std::string long_prop = nmea_wrap(
      "PIXSE,POSITI,1.00000000000000000000000000000000000,"
      "2.00000000000000000000000000000,3.0");
  ASSERT_GT(long_prop.size(), 82u);
  ASSERT_LT(long_prop.size(), 120u);
  EXPECT_EQ(decode(long_prop, options).records.size(), 1u);
  options.max_proprietary_sentence_chars = 82;
  EXPECT_EQ(decode(long_prop, options).stats.malformed, 1u);
  // A runaway sentence without terminator is cut at the buffer size and the decoder recovers.
  const Result runaway = decode("$PIXSE," + std::string(5000, 'A') + "$HEHDT,41.87,T*25\r\n");
  EXPECT_EQ(runaway.records.size(), 1u);
  EXPECT_EQ(runaway.stats.malformed, 1u);
}

TEST(Nmea, MissingChecksumConfigurable) {
  const std::string text = "$HEHDT,41.87,T\r\n";
  const Result strict = decode(text);
  EXPECT_TRUE(strict.records.empty());
  EXPECT_EQ(strict.stats.malformed, 1u);
  NmeaOptions lax;
  lax.require_checksum = false;
  EXPECT_EQ(decode(text, lax).records.size(), 1u);
  // A malformed checksum field is never accepted.
  EXPECT_EQ(decode("$HEHDT,41.87,T*2\r\n", lax).stats.malformed, 1u);
  // Lower-case hex digits are accepted (seen in the field).
  EXPECT_EQ(decode("$PIXSE,ATITUD,-1.641,-0.490*6d\r\n").records.size(), 1u);
}

std::string mixed_stream() {
  std::string text = join_crlf(kIxblueSentences);
  text += std::string("\x00\x13garbage\xfe", 10);
  text += "$HEHDT,41.87,T*26\r\n";  // bad checksum
  text += "$PIXSE,ATITUD,1.0";      // truncated
  text += join_crlf(kUnsupported);
  text += nmea_wrap("PIXSE,SPEED_,999.0,0,0");  // out of range
  text += "\n\n\r";
  text += join_crlf(kIxblueSentences);
  return text;
}

TEST(Nmea, SplitAtEveryByteGivesIdenticalOutput) {
  const std::string text = mixed_stream();
  const Result whole = decode(text);
  EXPECT_EQ(whole.records.size(), 2 * kIxblueSentences.size());
  EXPECT_EQ(whole.stats.checksum_failures, 1u);
  EXPECT_EQ(whole.stats.out_of_range, 1u);
  for (std::size_t split = 0; split <= text.size(); ++split) {
    NmeaDecoder decoder;
    std::vector<NmeaRecord> records;
    const auto* data = reinterpret_cast<const uint8_t*>(text.data());
    decoder.feed({data, split}, kHost, records);
    decoder.feed({data + split, text.size() - split}, kHost, records);
    ASSERT_EQ(describe(records), describe(whole.records)) << "split at " << split;
    expect_same_stats(decoder.stats(), whole.stats);
  }
  // Byte by byte too.
  NmeaDecoder decoder;
  std::vector<NmeaRecord> records;
  for (const char c : text) {
    const auto byte = static_cast<uint8_t>(c);
    decoder.feed({&byte, 1}, kHost, records);
  }
  EXPECT_EQ(describe(records), describe(whole.records));
  expect_same_stats(decoder.stats(), whole.stats);
}

TEST(Nmea, EncoderRoundTripEveryRecordType) {
  const Result first = decode(join_crlf(kIxblueSentences) + nmea_wrap("PIXSE,HEADNG,12.345") +
                              nmea_wrap("PHTRO,2.50,P,10.00,T"));
  ASSERT_EQ(first.records.size(), kIxblueSentences.size() + 2);
  const std::string encoded = describe(first.records);
  const Result second = decode(encoded);
  ASSERT_EQ(second.records.size(), first.records.size());
  EXPECT_EQ(second.stats.dropped_bytes, 0u);
  EXPECT_EQ(describe(second.records), encoded);
  // The HDT talker and the exact wire text of the real sentences survive.
  EXPECT_EQ(encode_nmea(first.records[0]), "$HEHDT,41.870,T*15\r\n");
  EXPECT_EQ(encode_nmea(first.records[9]), "$PIXSE,ALGSTS,00000045,00004000*60\r\n");
  EXPECT_EQ(encode_nmea(first.records[10]), "$PIXSE,STATUS,00000000,00000000*6F\r\n");
}

TEST(Nmea, OptionsValidate) {
  EXPECT_EQ(NmeaOptions{}.validate(), "");
  NmeaOptions bad;
  bad.max_sentence_chars = 5;
  EXPECT_NE(bad.validate().find("max_sentence_chars"), std::string::npos);
  bad = NmeaOptions{};
  bad.max_proprietary_sentence_chars = 40;
  EXPECT_NE(bad.validate().find("max_proprietary_sentence_chars"), std::string::npos);
  bad = NmeaOptions{};
  bad.max_speed_mps = -1.0;
  EXPECT_NE(bad.validate().find("max_speed_mps"), std::string::npos);
}

}  // namespace
}  // namespace nav::drivers
