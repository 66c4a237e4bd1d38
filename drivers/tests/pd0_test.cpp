// Tests of the RDI PD0 codec: hand-checkable synthetic ensembles first (round trip, framing
// errors, range checks, every-byte splits), then the real recordings in shared/data/dvl
// against the *.expected.csv values decoded by dolfyn (an independent decoder).
#include "nav/drivers/codecs/pd0.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "nav/testing/data.h"

namespace nav::drivers {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
const HostTime kHost{111, 222};

/// A bottom-tracking ensemble with every field set to a known value.
Pd0Ensemble sample_ensemble(uint32_t number = 70001) {
  Pd0Ensemble e;
  e.ensemble_number = number;                 // > 65535: exercises the MSB byte
  e.time.sensor_time_us = 1495627373'900000;  // 2017-05-24T12:02:53.90Z
  e.fixed.firmware_version = 51;
  e.fixed.firmware_revision = 41;
  e.fixed.system_config = 0x414B;
  e.fixed.num_beams = 4;
  e.fixed.num_cells = 17;
  e.fixed.pings_per_ensemble = 100;
  e.fixed.cell_length_m = 0.88;
  e.fixed.blank_m = 1.76;
  e.fixed.bin1_distance_m = 2.09;
  e.fixed.coord_transform = 0x1F;  // earth, tilts, 3-beam, bin mapping
  e.fixed.serial_number = 12345;
  e.fixed.beam_angle_deg = 20;
  e.heading_rad = 321.18 * kDeg;
  e.pitch_rad = -3.25 * kDeg;
  e.roll_rad = 1.5 * kDeg;
  e.temperature_c = -1.23;
  e.salinity_ppt = 35.0;
  e.sound_speed_mps = 1480.0;
  e.depth_m = 123.4;
  e.pressure_dbar = 124.567;
  e.bit_result = 0;
  Pd0BottomTrack bt;
  bt.pings_per_ensemble = 1;
  bt.velocity_mps = {0.052, -0.062, 0.091, std::nullopt};
  bt.range_m = {6.86, 10.39, 700.01, std::nullopt};  // 700.01 m needs the range MSB byte
  bt.correlation = {255, 254, 253, 252};
  bt.eval_amplitude = {100, 101, 102, 103};
  bt.percent_good = {0, 0, 0, 100};
  e.bottom_track = bt;
  return e;
}

void expect_near_opt(const std::optional<double>& a, const std::optional<double>& b, double tol,
                     const std::string& what) {
  ASSERT_EQ(a.has_value(), b.has_value()) << what;
  if (a) {
    EXPECT_NEAR(*a, *b, tol) << what;
  }
}

/// Field-by-field comparison of two decoded ensembles (tolerance: below wire resolution).
void expect_same(const Pd0Ensemble& a, const Pd0Ensemble& b) {
  constexpr double tol = 1e-9;
  EXPECT_EQ(a.ensemble_number, b.ensemble_number);
  EXPECT_EQ(a.time.sensor_time_us, b.time.sensor_time_us);
  EXPECT_EQ(a.fixed.firmware_version, b.fixed.firmware_version);
  EXPECT_EQ(a.fixed.firmware_revision, b.fixed.firmware_revision);
  EXPECT_EQ(a.fixed.system_config, b.fixed.system_config);
  EXPECT_EQ(a.fixed.num_beams, b.fixed.num_beams);
  EXPECT_EQ(a.fixed.num_cells, b.fixed.num_cells);
  EXPECT_EQ(a.fixed.pings_per_ensemble, b.fixed.pings_per_ensemble);
  EXPECT_NEAR(a.fixed.cell_length_m, b.fixed.cell_length_m, tol);
  EXPECT_NEAR(a.fixed.blank_m, b.fixed.blank_m, tol);
  EXPECT_NEAR(a.fixed.bin1_distance_m, b.fixed.bin1_distance_m, tol);
  EXPECT_EQ(a.fixed.coord_transform, b.fixed.coord_transform);
  EXPECT_EQ(a.fixed.sensor_source, b.fixed.sensor_source);
  EXPECT_EQ(a.fixed.sensors_available, b.fixed.sensors_available);
  EXPECT_EQ(a.fixed.serial_number, b.fixed.serial_number);
  EXPECT_EQ(a.fixed.beam_angle_deg, b.fixed.beam_angle_deg);
  expect_near_opt(a.heading_rad, b.heading_rad, tol, "heading");
  expect_near_opt(a.pitch_rad, b.pitch_rad, tol, "pitch");
  expect_near_opt(a.roll_rad, b.roll_rad, tol, "roll");
  expect_near_opt(a.temperature_c, b.temperature_c, tol, "temperature");
  expect_near_opt(a.salinity_ppt, b.salinity_ppt, tol, "salinity");
  expect_near_opt(a.sound_speed_mps, b.sound_speed_mps, tol, "sound speed");
  expect_near_opt(a.depth_m, b.depth_m, tol, "depth");
  expect_near_opt(a.pressure_dbar, b.pressure_dbar, tol, "pressure");
  EXPECT_EQ(a.bit_result, b.bit_result);
  ASSERT_EQ(a.bottom_track.has_value(), b.bottom_track.has_value());
  if (a.bottom_track) {
    const auto &x = *a.bottom_track, &y = *b.bottom_track;
    EXPECT_EQ(x.pings_per_ensemble, y.pings_per_ensemble);
    for (int i = 0; i < 4; ++i) {
      expect_near_opt(x.velocity_mps[i], y.velocity_mps[i], tol,
                      "bt velocity " + std::to_string(i));
      expect_near_opt(x.range_m[i], y.range_m[i], tol, "bt range " + std::to_string(i));
    }
    EXPECT_EQ(x.correlation, y.correlation);
    EXPECT_EQ(x.eval_amplitude, y.eval_amplitude);
    EXPECT_EQ(x.percent_good, y.percent_good);
  }
}

std::vector<Pd0Ensemble> decode_all(const std::vector<uint8_t>& bytes, Pd0Decoder& decoder) {
  std::vector<Pd0Ensemble> out;
  decoder.feed(bytes, kHost, out);
  return out;
}

void append(std::vector<uint8_t>& to, const std::vector<uint8_t>& bytes) {
  to.insert(to.end(), bytes.begin(), bytes.end());
}

std::vector<uint8_t> read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void expect_stats_equal(const DecodeStats& a, const DecodeStats& b) {
  EXPECT_EQ(a.to_json(), b.to_json());
}

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

/// Rewrites the checksum of an encoded ensemble after a test edited its bytes.
void fix_checksum(std::vector<uint8_t>& bytes) {
  const std::size_t n = bytes.size() - 2;
  const uint16_t sum = pd0_checksum({bytes.data(), n});
  bytes[n] = uint8_t(sum & 0xFF);
  bytes[n + 1] = uint8_t(sum >> 8);
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

/// Decodes `stream` split in two at every byte boundary and byte by byte; every way must give
/// the same ensembles and the same counters as a single feed.
void expect_split_invariant(const std::vector<uint8_t>& stream) {
  Pd0Decoder whole;
  const auto reference = decode_all(stream, whole);
  for (std::size_t k = 0; k <= stream.size(); ++k) {
    Pd0Decoder split;
    std::vector<Pd0Ensemble> out;
    split.feed({stream.data(), k}, kHost, out);
    split.feed({stream.data() + k, stream.size() - k}, kHost, out);
    ASSERT_EQ(out.size(), reference.size()) << "split at " << k;
    for (std::size_t i = 0; i < out.size(); ++i) expect_same(out[i], reference[i]);
    expect_stats_equal(split.stats(), whole.stats());
    ASSERT_EQ(split.buffered_bytes(), whole.buffered_bytes());
  }
  Pd0Decoder bytewise;
  std::vector<Pd0Ensemble> out;
  for (uint8_t b : stream) bytewise.feed({&b, 1}, kHost, out);
  ASSERT_EQ(out.size(), reference.size());
  expect_stats_equal(bytewise.stats(), whole.stats());
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

// ---------------------------------------------------------------- real recordings

struct CsvRow {
  std::vector<std::string> text;  ///< as printed, for the precision
  std::vector<double> value;
};

/// Reads an expected.csv: comment line with the frame, header line, rows.
std::vector<CsvRow> read_csv(const std::filesystem::path& path, std::string& frame_line) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, frame_line);
  std::getline(in, line);  // column names
  std::vector<CsvRow> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    CsvRow row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) {
      row.text.push_back(cell);
      row.value.push_back(std::stod(cell));
    }
    rows.push_back(row);
  }
  return rows;
}

/// Half a unit of the last printed decimal (plus rounding slack of the csv writer).
double printed_tolerance(const std::string& text) {
  const auto dot = text.find('.');
  const int decimals = dot == std::string::npos ? 0 : int(text.size() - dot - 1);
  return 0.5 * std::pow(10.0, -decimals) + 1e-9;
}

std::optional<double> to_deg(const std::optional<double>& rad) {
  return rad ? std::optional<double>(*rad / kDeg) : std::nullopt;
}

void expect_matches_csv(const Pd0Ensemble& e, const CsvRow& row, bool with_bt) {
  const auto check = [&](std::optional<double> got, std::size_t col, const char* what) {
    ASSERT_TRUE(got.has_value()) << what << " ensemble " << row.text[0];
    EXPECT_NEAR(*got, row.value[col], printed_tolerance(row.text[col]))
        << what << " ensemble " << row.text[0];
  };
  EXPECT_EQ(e.ensemble_number, uint32_t(row.value[0]));
  ASSERT_TRUE(e.time.sensor_time_us);
  EXPECT_NEAR(double(*e.time.sensor_time_us) / 1e6, row.value[1], printed_tolerance(row.text[1]));
  check(to_deg(e.heading_rad), 2, "heading");
  check(to_deg(e.pitch_rad), 3, "pitch");
  check(to_deg(e.roll_rad), 4, "roll");
  check(e.temperature_c, 5, "temperature");
  check(e.sound_speed_mps, 6, "sound speed");
  check(e.depth_m, 7, "depth");
  check(e.pressure_dbar, 8, "pressure");
  if (!with_bt) return;
  ASSERT_TRUE(e.bottom_track);
  for (int b = 0; b < 4; ++b) {
    const std::size_t vcol = 9 + std::size_t(b), rcol = 13 + std::size_t(b);
    if (row.value[vcol] == -32.768) {
      EXPECT_FALSE(e.bottom_track->velocity_mps[b]) << "bt velocity " << b;
    } else {
      check(e.bottom_track->velocity_mps[b], vcol, "bt velocity");
    }
    if (row.value[rcol] == 0.0) {
      EXPECT_FALSE(e.bottom_track->range_m[b]) << "bt range " << b;
    } else {
      check(e.bottom_track->range_m[b], rcol, "bt range");
    }
  }
}

/// Decodes a file in chunks; `buffered` is what is left waiting at the end (a cut ensemble).
std::vector<Pd0Ensemble> decode_file(const std::filesystem::path& path, DecodeStats& stats,
                                     std::size_t& buffered, std::size_t chunk = 4096) {
  const std::vector<uint8_t> bytes = read_file(path);
  Pd0Decoder decoder;
  std::vector<Pd0Ensemble> out;
  for (std::size_t i = 0; i < bytes.size(); i += chunk) {
    decoder.feed({bytes.data() + i, std::min(chunk, bytes.size() - i)}, kHost, out);
  }
  stats = decoder.stats();
  buffered = decoder.buffered_bytes();
  EXPECT_EQ(stats.bytes, bytes.size());
  EXPECT_EQ(stats.records, out.size());
  return out;
}

/// Re-encoding a decoded ensemble and decoding it again gives the same values.
void expect_reencode_round_trip(const std::vector<Pd0Ensemble>& ensembles) {
  for (const Pd0Ensemble& e : ensembles) {
    Pd0Decoder decoder;
    const auto again = decode_all(encode_pd0(e), decoder);
    ASSERT_EQ(again.size(), 1u);
    expect_same(again[0], e);
  }
}

TEST(Pd0RealData, RdiWithBottomTrackMatchesDolfyn) {
  NAV_REQUIRE_DATA(path, "dvl/RDI_withBT.000");
  NAV_REQUIRE_DATA(csv, "dvl/RDI_withBT.expected.csv");
  DecodeStats stats;
  std::size_t buffered = 0;
  const auto ensembles = decode_file(path, stats, buffered);
  ASSERT_EQ(ensembles.size(), 1721u);
  EXPECT_EQ(buffered, 99u);  // the file ends 99 bytes into ensemble 1722
  EXPECT_EQ(stats.checksum_failures, 0u);
  EXPECT_EQ(stats.malformed, 0u);
  EXPECT_EQ(stats.dropped_bytes, 0u);
  EXPECT_EQ(stats.out_of_range, 0u);
  std::size_t bt_valid = 0;
  std::optional<uint32_t> first_valid;
  for (const auto& e : ensembles) {
    ASSERT_TRUE(e.bottom_track);
    EXPECT_EQ(e.coord_frame(), Pd0CoordFrame::kEarth);
    if (e.bottom_track->velocity_valid()) {
      ++bt_valid;
      if (!first_valid) first_valid = e.ensemble_number;
    }
  }
  EXPECT_EQ(bt_valid, 898u);
  EXPECT_EQ(first_valid, 508u);

  std::string frame_line;
  const auto rows = read_csv(csv, frame_line);
  EXPECT_NE(frame_line.find("earth"), std::string::npos);
  ASSERT_EQ(rows.size(), 100u);
  for (std::size_t i = 0; i < rows.size(); ++i) expect_matches_csv(ensembles[i], rows[i], true);

  // Ensemble 508, the first with valid bottom track, against the bytes read by hand from the
  // file (BT range 686/1039/753/905 cm, velocity 52/62/91/-3 mm/s, heading 32118 = 321.18 deg,
  // Y2K RTC 2017-05-24 12:02:53.90).
  const Pd0Ensemble& e = ensembles[507];
  ASSERT_EQ(e.ensemble_number, 508u);
  const auto& bt = *e.bottom_track;
  const double ranges[4] = {6.86, 10.39, 7.53, 9.05}, vels[4] = {0.052, 0.062, 0.091, -0.003};
  for (int b = 0; b < 4; ++b) {
    EXPECT_NEAR(*bt.range_m[b], ranges[b], 1e-9);
    EXPECT_NEAR(*bt.velocity_mps[b], vels[b], 1e-9);
  }
  EXPECT_NEAR(*e.heading_rad / kDeg, 321.18, 1e-9);
  EXPECT_EQ(*e.time.sensor_time_us, 1495627373'900000);
  expect_reencode_round_trip(ensembles);
}

TEST(Pd0RealData, RdiTest01BeamCoordinatesMatchDolfyn) {
  NAV_REQUIRE_DATA(path, "dvl/RDI_test01.000");
  NAV_REQUIRE_DATA(csv, "dvl/RDI_test01.expected.csv");
  DecodeStats stats;
  std::size_t buffered = 0;
  const auto ensembles = decode_file(path, stats, buffered, 333);
  ASSERT_EQ(ensembles.size(), 22u);
  EXPECT_EQ(buffered, 772u);  // the file ends 772 bytes into ensemble 23
  EXPECT_EQ(stats.checksum_failures, 0u);
  EXPECT_EQ(stats.dropped_bytes, 0u);
  std::string frame_line;
  const auto rows = read_csv(csv, frame_line);
  EXPECT_NE(frame_line.find("beam"), std::string::npos);
  ASSERT_EQ(rows.size(), 22u);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(ensembles[i].coord_frame(), Pd0CoordFrame::kBeam);
    EXPECT_FALSE(ensembles[i].bottom_track);
    expect_matches_csv(ensembles[i], rows[i], false);
  }
  expect_reencode_round_trip(ensembles);
}

TEST(Pd0RealData, WinRiverFileDecodesCompletely) {
  NAV_REQUIRE_DATA(path, "dvl/winriver01.PD0");
  DecodeStats stats;
  std::size_t buffered = 0;
  const auto ensembles = decode_file(path, stats, buffered, 1000);
  ASSERT_EQ(ensembles.size(), 262u);
  EXPECT_EQ(buffered, 0u);
  EXPECT_EQ(stats.checksum_failures, 0u);
  EXPECT_EQ(stats.dropped_bytes, 0u);
  EXPECT_EQ(stats.malformed, 0u);
  std::size_t bt_valid = 0;
  for (const auto& e : ensembles) {
    ASSERT_TRUE(e.bottom_track);
    if (e.bottom_track->velocity_valid()) ++bt_valid;
    ASSERT_TRUE(e.heading_rad && e.time.sensor_time_us);
  }
  EXPECT_EQ(bt_valid, 251u);
  expect_reencode_round_trip(ensembles);
}

TEST(Pd0RealData, SplitAtEveryByteOnRealEnsembles) {
  NAV_REQUIRE_DATA(path, "dvl/RDI_withBT.000");
  const std::vector<uint8_t> bytes = read_file(path);
  // Three ensembles around the first valid bottom track, with garbage in front.
  DecodeStats stats;
  std::size_t offset = 0;
  for (int k = 0; k < 506; ++k)
    offset += std::size_t(bytes[offset + 2] | (bytes[offset + 3] << 8)) + 2;
  std::size_t end = offset;
  for (int k = 0; k < 3; ++k) end += std::size_t(bytes[end + 2] | (bytes[end + 3] << 8)) + 2;
  std::vector<uint8_t> stream = {0x7F, 0x00, 0x7F};
  stream.insert(stream.end(), bytes.begin() + std::ptrdiff_t(offset),
                bytes.begin() + std::ptrdiff_t(end));
  expect_split_invariant(stream);
  Pd0Decoder decoder;
  const auto out = decode_all(stream, decoder);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[1].ensemble_number, 508u);
  EXPECT_EQ(decoder.stats().dropped_bytes, 3u);
}

}  // namespace
}  // namespace nav::drivers
