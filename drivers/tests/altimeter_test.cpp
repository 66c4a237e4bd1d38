// Altimeter ASCII codecs: Tritech PA500 "ddd.ddm", Valeport VA500 $PRVAT (manual examples),
// Impact Subsea ISA500 default and custom strings, NMEA DBT; no-echo sentinels and range flags,
// checksums, garbage, chunking independence and encoder round trips.
#include "nav/drivers/codecs/altimeter.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "ascii_decode_support.h"
#include "nav/drivers/codecs/nmea.h"

namespace nav::drivers {
namespace {

const HostTime kHost{9, 10};

using Result = test::DecodeResult<AltimeterRecord>;

Result decode(const std::string& text, const AltimeterFormat& format) {
  return test::decode_text<AltimeterDecoder, AltimeterRecord>(text, format, kHost);
}

AltimeterFormat format_of(AltimeterProtocol protocol) {
  AltimeterFormat format;
  format.protocol = protocol;
  return format;
}

std::string describe(const std::vector<AltimeterRecord>& records, const AltimeterFormat& f) {
  std::string text;
  for (const auto& r : records) {
    text += std::to_string(static_cast<int>(r.status)) + ":" + encode_altimeter(r, f);
  }
  return text;
}

TEST(Altimeter, TritechPa500) {
  const auto format = format_of(AltimeterProtocol::kTritechPa500);
  const Result r = decode("012.34m\r\n000.00m\r\n099.99m\r\n500.00m\r\n001.50M\r\n", format);
  ASSERT_EQ(r.records.size(), 5u);
  EXPECT_EQ(r.records[0].status, AltimeterStatus::kValid);
  ASSERT_TRUE(r.records[0].range_m.has_value());
  EXPECT_DOUBLE_EQ(*r.records[0].range_m, 12.34);
  EXPECT_EQ(r.records[0].time.host.monotonic_us, 9);
  // 0 and 99.99 are "no echo", not ranges; 500 m is beyond the instrument.
  EXPECT_EQ(r.records[1].status, AltimeterStatus::kNoEcho);
  EXPECT_FALSE(r.records[1].range_m.has_value());
  EXPECT_EQ(r.records[2].status, AltimeterStatus::kNoEcho);
  EXPECT_EQ(r.records[3].status, AltimeterStatus::kOutOfRange);
  EXPECT_FALSE(r.records[3].range_m.has_value());
  EXPECT_DOUBLE_EQ(r.records[3].raw_value_m, 500.0);
  EXPECT_DOUBLE_EQ(*r.records[4].range_m, 1.5);
  EXPECT_EQ(r.stats.out_of_range, 1u);
  EXPECT_EQ(r.stats.dropped_bytes, 0u);
}

TEST(Altimeter, ValeportVa500ManualExamples) {
  const auto format = format_of(AltimeterProtocol::kValeportNmea);
  // VA500 operating manual section 4.1 examples (lower-case checksum digits as printed).
  const Result r = decode(
      "$PRVAT,00.115,M,0010.073,dBar*39\r\n$PRVAT,00.116,M,0010.056,dBar*3d\r\n"
      "$PRVAT,00.114,M,0010.083,dBar*37\r\n",
      format);
  EXPECT_EQ(r.stats.checksum_failures, 0u);
  ASSERT_EQ(r.records.size(), 3u);
  EXPECT_DOUBLE_EQ(*r.records[0].range_m, 0.115);
  ASSERT_TRUE(r.records[0].pressure_pa.has_value());
  EXPECT_NEAR(*r.records[0].pressure_pa, 100730.0, 1e-6);
  // Without the optional pressure sensor the pressure field is empty.
  const Result no_p = decode(nmea_wrap("PRVAT,12.500,M,,dBar"), format);
  ASSERT_EQ(no_p.records.size(), 1u);
  EXPECT_FALSE(no_p.records[0].pressure_pa.has_value());
  EXPECT_DOUBLE_EQ(*no_p.records[0].range_m, 12.5);
}

TEST(Altimeter, ValeportPressureNoSensorCanReadIsMalformed) {
  // A pressure beyond the deepest ocean (here a run of digits a fuzzer found, 5.6e53 dbar) is
  // corruption, not a reading: the sentence is dropped and counted, not passed on.
  const auto format = format_of(AltimeterProtocol::kValeportNmea);
  const Result corrupt =
      decode(nmea_wrap("PRVAT,00.116,M," + std::string(54, '5') + ",dBar") +
                 nmea_wrap("PRVAT,00.116,M,12000.5,dBar") + nmea_wrap("PRVAT,00.116,M,-20.5,dBar"),
             format);
  EXPECT_TRUE(corrupt.records.empty());
  EXPECT_EQ(corrupt.stats.malformed, 3u);
  // The extremes a sensor can report still decode: the deepest trench, a gauge reading in air.
  const Result deep = decode(
      nmea_wrap("PRVAT,10.000,M,11000.000,dBar") + nmea_wrap("PRVAT,10.000,M,-0.100,dBar"),
      format);
  ASSERT_EQ(deep.records.size(), 2u);
  EXPECT_NEAR(*deep.records[0].pressure_pa, 1.1e8, 1e-3);
  EXPECT_NEAR(*deep.records[1].pressure_pa, -1.0e3, 1e-6);
}

TEST(Altimeter, NmeaDbtManualExampleAndFallbackUnits) {
  const auto format = format_of(AltimeterProtocol::kNmeaDbt);
  // VA500 manual section 4.2 example.
  const Result r = decode("$SDDBT,0.4,f,0.1,M,0.1,F*02\r\n", format);
  EXPECT_EQ(r.stats.checksum_failures, 0u);
  ASSERT_EQ(r.records.size(), 1u);
  EXPECT_DOUBLE_EQ(*r.records[0].range_m, 0.1);
  // Metres field empty: feet are used, then fathoms.
  const Result f = decode(nmea_wrap("SDDBT,32.8,f,,M,,F") + nmea_wrap("SDDBT,,f,,M,2.0,F"), format);
  ASSERT_EQ(f.records.size(), 2u);
  EXPECT_NEAR(*f.records[0].range_m, 32.8 * 0.3048, 1e-12);
  EXPECT_NEAR(*f.records[1].range_m, 2.0 * 1.8288, 1e-12);
  // Other well-formed sentences on the line are counted unsupported.
  const Result other = decode(nmea_wrap("GPGGA,1,2") + nmea_wrap("SDDPT,1.0,0.0"), format);
  EXPECT_TRUE(other.records.empty());
  EXPECT_EQ(other.stats.unsupported, 2u);
}

TEST(Altimeter, Isa500DefaultAndCustomStrings) {
  const auto format = format_of(AltimeterProtocol::kImpactSubseaIsa500);
  const Result r = decode("012.345 m\r\n  7.5m\r\n", format);
  ASSERT_EQ(r.records.size(), 2u);
  EXPECT_DOUBLE_EQ(*r.records[0].range_m, 12.345);
  EXPECT_DOUBLE_EQ(*r.records[1].range_m, 7.5);
  AltimeterFormat custom = format;
  custom.prefix = "ALT=";
  custom.suffix = "";
  const Result c = decode("ALT=3.250\r\nALT:3.25\r\n", custom);
  ASSERT_EQ(c.records.size(), 1u);
  EXPECT_DOUBLE_EQ(*c.records[0].range_m, 3.25);
  EXPECT_EQ(c.stats.malformed, 1u);
}

TEST(Altimeter, ChecksumsGarbageAndMalformed) {
  const auto nmea = format_of(AltimeterProtocol::kValeportNmea);
  const std::string good = "$PRVAT,00.115,M,0010.073,dBar*39\r\n";
  const Result r =
      decode(std::string("\x00\xffjunk", 6) + good + "$PRVAT,00.115,M,0010.073,dBar*38\r\n" +
                 "$PRVAT,00.1x5,M,0010.073,dBar*" + "00\r\n" + good,
             nmea);
  ASSERT_EQ(r.records.size(), 2u);
  EXPECT_EQ(r.stats.checksum_failures, 2u);
  EXPECT_EQ(r.stats.bytes, 2 * good.size() + r.stats.dropped_bytes);
  const auto pa500 = format_of(AltimeterProtocol::kTritechPa500);
  const Result p =
      decode("12.34\r\nm\r\nabc.dem\r\n12.34m" + std::string("\x02") + "12.34m\r\n", pa500);
  ASSERT_EQ(p.records.size(), 1u);
  EXPECT_EQ(p.stats.malformed, 4u);
}

TEST(Altimeter, SplitAtEveryByteGivesIdenticalOutput) {
  for (const auto protocol :
       {AltimeterProtocol::kTritechPa500, AltimeterProtocol::kValeportNmea,
        AltimeterProtocol::kImpactSubseaIsa500, AltimeterProtocol::kNmeaDbt}) {
    const auto format = format_of(protocol);
    std::string text = "\x01garbage\r\n";
    for (const double v : {12.34, 0.0, 450.0, 3.5}) {
      text += encode_altimeter(
          {{},
           {},
           {},
           protocol == AltimeterProtocol::kValeportNmea ? std::optional<double>(2.0e5)
                                                        : std::nullopt,
           v},
          format);
      text += "$bad\r\n";
    }
    const Result whole = decode(text, format);
    EXPECT_EQ(whole.records.size(), 4u) << static_cast<int>(protocol);
    for (std::size_t split = 0; split <= text.size(); ++split) {
      AltimeterDecoder decoder(format);
      std::vector<AltimeterRecord> records;
      const auto* data = reinterpret_cast<const uint8_t*>(text.data());
      decoder.feed({data, split}, kHost, records);
      decoder.feed({data + split, text.size() - split}, kHost, records);
      ASSERT_EQ(describe(records, format), describe(whole.records, format)) << split;
      ASSERT_EQ(decoder.stats().to_json(), whole.stats.to_json()) << split;
    }
  }
}

TEST(Altimeter, EncoderRoundTrip) {
  for (const auto protocol : {AltimeterProtocol::kTritechPa500, AltimeterProtocol::kValeportNmea,
                              AltimeterProtocol::kImpactSubseaIsa500}) {
    const auto format = format_of(protocol);
    const AltimeterRecord record{{}, AltimeterStatus::kValid, 42.25, std::nullopt, 42.25};
    const std::string text = encode_altimeter(record, format);
    const Result r = decode(text, format);
    ASSERT_EQ(r.records.size(), 1u) << text;
    EXPECT_DOUBLE_EQ(*r.records[0].range_m, 42.25);
    EXPECT_EQ(encode_altimeter(r.records[0], format), text);
  }
  EXPECT_EQ(encode_altimeter({{}, {}, {}, {}, 12.34}, {}), "012.34m\r\n");
}

TEST(Altimeter, FormatValidate) {
  EXPECT_EQ(AltimeterFormat{}.validate(), "");
  AltimeterFormat bad;
  bad.min_range_m = 10.0;
  bad.max_range_m = 5.0;
  EXPECT_NE(bad.validate().find("min_range_m"), std::string::npos);
  bad = AltimeterFormat{};
  bad.prefix = std::string("\x01", 1);
  EXPECT_NE(bad.validate().find("printable"), std::string::npos);
}

}  // namespace
}  // namespace nav::drivers
