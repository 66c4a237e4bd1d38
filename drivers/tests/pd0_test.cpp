// Tests of the RDI PD0 codec on hand-checkable synthetic ensembles: layout, round trip, range
// checks, framing errors, resynchronisation and every-byte splits. The real recordings are
// tested in pd0_real_data_test.cpp, ensembles with many data types in pd0_data_types_test.cpp.
#include "nav/drivers/codecs/pd0.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "pd0_test_support.h"

namespace nav::drivers {
namespace {

using namespace pd0_test;

// ---------------------------------------------------------------- synthetic ensembles

TEST(Pd0Codec, EncodedEnsembleHasTheManualsLayout) {
  const std::vector<uint8_t> bytes = encode_pd0(sample_ensemble());
  ASSERT_EQ(bytes.size(), 6u + 2 * 3 + 59 + 65 + 85 + 2);
  EXPECT_EQ(bytes[0], 0x7F);
  EXPECT_EQ(bytes[1], 0x7F);
  EXPECT_EQ(bytes[2] | (bytes[3] << 8), int(bytes.size()) - 2);
  EXPECT_EQ(bytes[5], 3);
  EXPECT_EQ(bytes[6] | (bytes[7] << 8), 12);  // fixed leader right after the table
  EXPECT_EQ(bytes[12 + 59], 0x80);            // variable leader ID 0x0080
  const std::size_t v = 12 + 59;
  EXPECT_EQ(bytes[v + 2] | (bytes[v + 3] << 8), 70001 & 0xFFFF);
  EXPECT_EQ(bytes[v + 11], 1);                             // ensemble MSB: 70001 = 1 * 65536 + 4465
  EXPECT_EQ(bytes[v + 18] | (bytes[v + 19] << 8), 32118);  // heading 321.18 deg
  EXPECT_EQ(bytes[v + 57], 20);                            // Y2K century
  EXPECT_EQ(bytes[v + 58], 17);
  const std::size_t b = v + 65;
  EXPECT_EQ(bytes[b], 0x00);
  EXPECT_EQ(bytes[b + 1], 0x06);                            // bottom track ID 0x0600
  EXPECT_EQ(bytes[b + 77 + 2], 1);                          // 70001 cm = 1 * 65536 + 4465
  EXPECT_EQ(bytes[b + 30] | (bytes[b + 31] << 8), 0x8000);  // beam 4 invalid velocity
  uint32_t sum = 0;
  for (std::size_t i = 0; i + 2 < bytes.size(); ++i) sum += bytes[i];
  EXPECT_EQ(bytes[bytes.size() - 2] | (bytes[bytes.size() - 1] << 8), int(sum & 0xFFFF));
}

TEST(Pd0Codec, RoundTripPreservesEveryField) {
  const Pd0Ensemble in = sample_ensemble();
  Pd0Decoder decoder;
  const auto out = decode_all(encode_pd0(in), decoder);
  ASSERT_EQ(out.size(), 1u);
  expect_same(out[0], in);
  EXPECT_EQ(out[0].coord_frame(), Pd0CoordFrame::kEarth);
  EXPECT_TRUE(out[0].fixed.tilts_used());
  EXPECT_FALSE(out[0].bottom_track->velocity_valid());
  EXPECT_EQ(out[0].time.host.monotonic_us, kHost.monotonic_us);
  EXPECT_EQ(out[0].time.host.realtime_us, kHost.realtime_us);
  EXPECT_EQ(decoder.stats().records, 1u);
  EXPECT_EQ(decoder.stats().out_of_range, 0u);
  EXPECT_EQ(decoder.stats().dropped_bytes, 0u);
  EXPECT_EQ(decoder.buffered_bytes(), 0u);
}

TEST(Pd0Codec, EnsembleWithoutBottomTrackAndEachCoordFrame) {
  for (uint8_t frame = 0; frame < 4; ++frame) {
    Pd0Ensemble in = sample_ensemble();
    in.bottom_track.reset();
    in.fixed.coord_transform = uint8_t(frame << 3);
    Pd0Decoder decoder;
    const auto out = decode_all(encode_pd0(in), decoder);
    ASSERT_EQ(out.size(), 1u);
    expect_same(out[0], in);
    EXPECT_EQ(int(out[0].coord_frame()), frame);
  }
  EXPECT_STREQ(to_string(Pd0CoordFrame::kBeam), "beam");
  EXPECT_STREQ(to_string(Pd0CoordFrame::kShip), "ship");
}

TEST(Pd0Codec, EmptyValuesAreWrittenSoTheyDecodeEmpty) {
  Pd0Ensemble in = sample_ensemble();
  in.heading_rad.reset();
  in.pitch_rad.reset();
  in.roll_rad.reset();
  in.temperature_c.reset();
  in.salinity_ppt.reset();
  in.sound_speed_mps.reset();
  in.time.sensor_time_us.reset();
  Pd0Decoder decoder;
  const auto out = decode_all(encode_pd0(in), decoder);
  ASSERT_EQ(out.size(), 1u);
  expect_same(out[0], in);
  EXPECT_EQ(decoder.stats().out_of_range, 1u);  // one record with rejected fields
}

constexpr std::size_t kVariableAt = 12 + 59;  // in encode_pd0 output with bottom track

TEST(Pd0Codec, UnknownDataTypesAreSkippedByTheOffsetTable) {
  // Insert a WinRiver-style type 0x2022 of 10 bytes between the variable leader and the
  // bottom track: the decoder must locate the bottom track through the offset table.
  const Pd0Ensemble in = sample_ensemble();
  const std::vector<uint8_t> plain = encode_pd0(in);
  const std::size_t bottom_at = 12 + 59 + 65;
  std::vector<uint8_t> bytes(plain.begin(), plain.begin() + 10);  // IDs .. 2 offsets
  bytes[5] = 4;
  const uint16_t offsets[4] = {14, 14 + 59, 14 + 59 + 65, 14 + 59 + 65 + 10};
  for (uint16_t o : offsets) bytes.insert(bytes.end(), {uint8_t(o & 0xFF), uint8_t(o >> 8)});
  bytes.erase(bytes.begin() + 6, bytes.begin() + 10);  // the encoder's old offsets
  bytes.insert(bytes.end(), plain.begin() + 12, plain.begin() + std::ptrdiff_t(bottom_at));
  bytes.insert(bytes.end(), {0x22, 0x20, 1, 2, 3, 4, 5, 6, 7, 8});
  bytes.insert(bytes.end(), plain.begin() + std::ptrdiff_t(bottom_at), plain.end());
  ASSERT_EQ(bytes.size(), plain.size() + 2 + 10);
  bytes[2] = uint8_t((bytes.size() - 2) & 0xFF);
  bytes[3] = uint8_t((bytes.size() - 2) >> 8);
  fix_checksum(bytes);
  Pd0Decoder decoder;
  const auto out = decode_all(bytes, decoder);
  ASSERT_EQ(out.size(), 1u);
  expect_same(out[0], in);
  EXPECT_EQ(out[0].skipped_type_ids, std::vector<uint16_t>{0x2022});
  EXPECT_EQ(decoder.stats().unsupported, 0u);
}

TEST(Pd0Codec, RangeChecksRejectAbsurdValuesAndCountThem) {
  // Write raw values the instrument never produces and check each is rejected on its own.
  // Offsets are the manual's 1-based byte positions in the variable leader minus one.
  struct Case {
    std::size_t offset;
    int size;  ///< 1 or 2 bytes (little-endian)
    uint16_t raw;
    const char* what;
  };
  const Case cases[] = {
      {18, 2, 36000, "heading 360.00 deg"},  {20, 2, uint16_t(-9001), "pitch -90.01 deg"},
      {22, 2, 9001, "roll 90.01 deg"},       {26, 2, 6000, "temperature 60 degC"},
      {24, 2, 41, "salinity 41 ppt"},        {14, 2, 1399, "sound speed 1399 m/s"},
      {14, 2, 1601, "sound speed 1601 m/s"}, {48, 2, uint16_t(-10001), "pressure -10.001 dbar"},
      {59, 1, 13, "Y2K RTC month 13"},       {60, 1, 31, "Y2K RTC 31 June"},
      {62, 1, 60, "Y2K RTC minute 60"},      {64, 1, 100, "Y2K RTC hundredths 100"}};
  for (const Case& c : cases) {
    std::vector<uint8_t> bytes = encode_pd0(sample_ensemble());
    uint8_t* v = bytes.data() + kVariableAt;
    if (c.offset == 60) v[59] = 6;             // June
    if (c.offset == 48) v[50] = v[51] = 0xFF;  // sign-extend to 32 bits
    v[c.offset] = uint8_t(c.raw & 0xFF);
    if (c.size == 2) v[c.offset + 1] = uint8_t(c.raw >> 8);
    fix_checksum(bytes);
    Pd0Decoder decoder;
    const auto out = decode_all(bytes, decoder);
    ASSERT_EQ(out.size(), 1u) << c.what;
    EXPECT_EQ(decoder.stats().out_of_range, 1u) << c.what;
    const Pd0Ensemble& e = out[0];
    const int empty = !e.heading_rad + !e.pitch_rad + !e.roll_rad + !e.temperature_c +
                      !e.salinity_ppt + !e.sound_speed_mps + !e.pressure_dbar +
                      !e.time.sensor_time_us;
    EXPECT_EQ(empty, 1) << c.what;
  }
}

TEST(Pd0Codec, TwoDigitYearRtcWhenThereIsNoY2kCentury) {
  std::vector<uint8_t> bytes = encode_pd0(sample_ensemble());
  bytes[kVariableAt + 57] = 0;  // no century: the 2-digit RTC (17 -> 2017) is used
  bytes[kVariableAt + 64] = 0;  // Y2K hundredths differ: proves which clock was read
  fix_checksum(bytes);
  Pd0Decoder decoder;
  auto out = decode_all(bytes, decoder);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].time.sensor_time_us, 1495627373'900000);
  bytes[kVariableAt + 4] = 97;  // 2-digit year 97 -> 1997
  fix_checksum(bytes);
  out = decode_all(bytes, decoder);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].time.sensor_time_us, 864475373'900000);  // 1997-05-24T12:02:53.90Z
}

TEST(Pd0Codec, BottomTrackRangeChecksAndInvalidMarkers) {
  Pd0Ensemble in = sample_ensemble();
  in.bottom_track->velocity_mps = {25.0, -0.5, std::nullopt, 0.0};  // 25 m/s is absurd
  in.bottom_track->range_m = {2500.0, 0.5, std::nullopt, 1999.99};  // 2.5 km is absurd
  Pd0Decoder decoder;
  const auto out = decode_all(encode_pd0(in), decoder);
  ASSERT_EQ(out.size(), 1u);
  const Pd0BottomTrack& bt = *out[0].bottom_track;
  EXPECT_FALSE(bt.velocity_mps[0]);
  EXPECT_NEAR(*bt.velocity_mps[1], -0.5, 1e-12);
  EXPECT_FALSE(bt.velocity_mps[2]);  // -32768 marker: invalid, not out of range
  EXPECT_NEAR(*bt.velocity_mps[3], 0.0, 1e-12);
  EXPECT_FALSE(bt.range_m[0]);
  EXPECT_NEAR(*bt.range_m[1], 0.5, 1e-12);
  EXPECT_FALSE(bt.range_m[2]);  // 0: no bottom detected
  EXPECT_NEAR(*bt.range_m[3], 1999.99, 1e-9);
  EXPECT_EQ(decoder.stats().out_of_range, 1u);
}

// ---------------------------------------------------------------- framing and resync

TEST(Pd0Decoder, FlippedBitFailsTheChecksumAndTheNextEnsembleIsFound) {
  const std::vector<uint8_t> good = encode_pd0(sample_ensemble(1));
  const std::vector<uint8_t> next = encode_pd0(sample_ensemble(2));
  // Every data byte (not the header IDs or byte count, which change the framing).
  for (std::size_t i = 4; i + 2 < good.size(); i += 7) {
    std::vector<uint8_t> stream = good;
    stream[i] ^= 0x10;
    append(stream, next);
    Pd0Decoder decoder;
    const auto out = decode_all(stream, decoder);
    ASSERT_EQ(out.size(), 1u) << "flipped byte " << i;
    EXPECT_EQ(out[0].ensemble_number, 2u);
    const DecodeStats& s = decoder.stats();
    EXPECT_EQ(s.checksum_failures + s.malformed >= 1, true) << i;
    EXPECT_EQ(s.dropped_bytes, good.size()) << i;
    EXPECT_EQ(s.bytes, stream.size());
  }
  std::vector<uint8_t> stream = good;
  stream[40] ^= 0x01;  // a fixed-leader byte: the offset table stays valid
  Pd0Decoder decoder;
  EXPECT_TRUE(decode_all(stream, decoder).empty());
  EXPECT_EQ(decoder.stats().checksum_failures, 1u);
}

TEST(Pd0Decoder, TruncatedEnsembleIsDroppedAndTheFollowingOneDecoded) {
  const std::vector<uint8_t> good = encode_pd0(sample_ensemble(1));
  for (std::size_t cut :
       {std::size_t(1), std::size_t(5), std::size_t(13), good.size() / 2, good.size() - 1}) {
    std::vector<uint8_t> stream(good.begin(), good.begin() + std::ptrdiff_t(cut));
    append(stream, encode_pd0(sample_ensemble(2)));
    append(stream, encode_pd0(sample_ensemble(3)));
    Pd0Decoder decoder;
    const auto out = decode_all(stream, decoder);
    ASSERT_GE(out.size(), 1u) << cut;
    EXPECT_EQ(out.back().ensemble_number, 3u) << cut;
    // The truncated piece and nothing else is dropped, unless it swallowed ensemble 2.
    if (out.size() == 2) {
      EXPECT_EQ(decoder.stats().dropped_bytes, cut) << cut;
    }
    EXPECT_EQ(decoder.stats().bytes, stream.size());
    EXPECT_EQ(decoder.buffered_bytes(), 0u);
  }
}

TEST(Pd0Decoder, GarbageBetweenEnsemblesIsDroppedAndCounted) {
  std::vector<uint8_t> stream;
  const std::vector<uint8_t> garbage = {0x00, 0x7F, 0x01, 0x7F, 0x7F, 0x05, 0x00, 0x00,
                                        0xFF, 0x7F, 0x7F, 0xFF, 0xFF, 0x01, 0x02, 0x03};
  std::size_t garbage_bytes = 0;
  for (uint32_t k = 1; k <= 4; ++k) {
    append(stream, garbage);
    garbage_bytes += garbage.size();
    append(stream, encode_pd0(sample_ensemble(k)));
  }
  Pd0Decoder decoder;
  const auto out = decode_all(stream, decoder);
  ASSERT_EQ(out.size(), 4u);
  for (uint32_t k = 0; k < 4; ++k) EXPECT_EQ(out[k].ensemble_number, k + 1);
  EXPECT_EQ(decoder.stats().dropped_bytes, garbage_bytes);
  EXPECT_GE(decoder.stats().malformed, 4u);  // the false 0x7F7F headers in the garbage
  EXPECT_EQ(decoder.stats().checksum_failures, 0u);
}

TEST(Pd0Decoder, UnsupportedAndMalformedEnsemblesAreCounted) {
  Pd0Ensemble e = sample_ensemble();
  e.bottom_track.reset();
  const std::vector<uint8_t> full = encode_pd0(e);  // header 10, fixed 59, variable 65
  // Checksum-valid ensemble with a fixed leader only (no variable leader): unsupported.
  std::vector<uint8_t> fixed_only(full.begin(), full.begin() + 10 + 59);
  fixed_only[5] = 1;
  fixed_only.erase(fixed_only.begin() + 8, fixed_only.begin() + 10);  // one offset
  fixed_only[6] = 8;
  fixed_only[2] = uint8_t(fixed_only.size());
  fixed_only[3] = 0;
  fixed_only.resize(fixed_only.size() + 2);
  fix_checksum(fixed_only);
  Pd0Decoder decoder;
  EXPECT_TRUE(decode_all(fixed_only, decoder).empty());
  EXPECT_EQ(decoder.stats().unsupported, 1u);
  EXPECT_EQ(decoder.stats().dropped_bytes, fixed_only.size());

  // Fixed leader cut to 20 bytes (its fields run past the next type): malformed.
  std::vector<uint8_t> cut(full.begin(), full.begin() + 10 + 20);
  cut.insert(cut.end(), full.begin() + 10 + 59, full.end());
  cut[8] = 10 + 20;
  cut[2] = uint8_t((cut.size() - 2) & 0xFF);
  cut[3] = uint8_t((cut.size() - 2) >> 8);
  fix_checksum(cut);
  Pd0Decoder decoder2;
  EXPECT_TRUE(decode_all(cut, decoder2).empty());
  EXPECT_GE(decoder2.stats().malformed, 1u);
  EXPECT_EQ(decoder2.stats().checksum_failures, 0u);
  EXPECT_EQ(decoder2.stats().dropped_bytes + decoder2.buffered_bytes(), cut.size());
}

TEST(Pd0Decoder, BufferIsBoundedByTheLargestEnsemble) {
  Pd0DecoderOptions options;
  options.max_ensemble_bytes = 300;
  ASSERT_TRUE(options.validate());
  Pd0Decoder decoder(options);
  // A header announcing 60000 bytes is rejected at once instead of waiting for them.
  std::vector<uint8_t> stream = {0x7F, 0x7F, 0x60, 0xEA, 0x00, 0x03};
  append(stream, encode_pd0(sample_ensemble(9)));
  std::vector<Pd0Ensemble> out;
  for (uint8_t b : stream) {
    decoder.feed({&b, 1}, kHost, out);
    EXPECT_LE(decoder.buffered_bytes(), options.max_ensemble_bytes);
  }
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].ensemble_number, 9u);
  EXPECT_EQ(decoder.stats().dropped_bytes, 6u);
  EXPECT_FALSE(Pd0DecoderOptions{.max_ensemble_bytes = 10}.validate());
  EXPECT_THROW(Pd0Decoder(Pd0DecoderOptions{.max_ensemble_bytes = 10}), std::invalid_argument);
}

TEST(Pd0Decoder, SplitAtEveryByteGivesIdenticalOutput) {
  std::vector<uint8_t> stream = {0x01, 0x7F, 0x7F, 0x02};
  append(stream, encode_pd0(sample_ensemble(1)));
  std::vector<uint8_t> bad = encode_pd0(sample_ensemble(2));
  bad[50] ^= 0xFF;
  append(stream, bad);
  append(stream, encode_pd0(sample_ensemble(3)));
  stream.insert(stream.end(), {0x7F, 0x7F, 0x10});  // trailing partial header
  expect_split_invariant(stream);
  Pd0Decoder decoder;
  EXPECT_EQ(decode_all(stream, decoder).size(), 2u);
  EXPECT_EQ(decoder.stats().bytes, decoder.stats().dropped_bytes + decoder.buffered_bytes() +
                                       2 * encode_pd0(sample_ensemble(1)).size());
}

}  // namespace
}  // namespace nav::drivers
