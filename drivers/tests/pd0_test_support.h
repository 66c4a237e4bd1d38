#pragma once
// Helpers shared by the PD0 codec tests (pd0_test.cpp, pd0_real_data_test.cpp,
// pd0_data_types_test.cpp): a fully populated sample ensemble, field-by-field comparison, checksum
// repair after byte edits and the every-byte split check. Included by relative path from the
// *_test.cpp beside it; test-only.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "nav/drivers/codecs/pd0.h"

namespace nav::drivers::pd0_test {

inline constexpr double kDeg = std::numbers::pi / 180.0;
inline const HostTime kHost{111, 222};

/// A bottom-tracking ensemble with every field set to a known value.
inline Pd0Ensemble sample_ensemble(uint32_t number = 70001) {
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

inline void expect_near_opt(const std::optional<double>& a, const std::optional<double>& b,
                            double tol, const std::string& what) {
  ASSERT_EQ(a.has_value(), b.has_value()) << what;
  if (a) {
    EXPECT_NEAR(*a, *b, tol) << what;
  }
}

/// Field-by-field comparison of two decoded ensembles (tolerance: below wire resolution).
inline void expect_same(const Pd0Ensemble& a, const Pd0Ensemble& b) {
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

inline std::vector<Pd0Ensemble> decode_all(const std::vector<uint8_t>& bytes, Pd0Decoder& decoder) {
  std::vector<Pd0Ensemble> out;
  decoder.feed(bytes, kHost, out);
  return out;
}

inline void append(std::vector<uint8_t>& to, const std::vector<uint8_t>& bytes) {
  to.insert(to.end(), bytes.begin(), bytes.end());
}

inline std::vector<uint8_t> read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

inline void expect_stats_equal(const DecodeStats& a, const DecodeStats& b) {
  EXPECT_EQ(a.to_json(), b.to_json());
}

/// Rewrites the checksum of an encoded ensemble after a test edited its bytes.
inline void fix_checksum(std::vector<uint8_t>& bytes) {
  const std::size_t n = bytes.size() - 2;
  const uint16_t sum = pd0_checksum({bytes.data(), n});
  bytes[n] = uint8_t(sum & 0xFF);
  bytes[n + 1] = uint8_t(sum >> 8);
}

/// Decodes `stream` split in two at every byte boundary and byte by byte; every way must give
/// the same ensembles and the same counters as a single feed.
inline void expect_split_invariant(const std::vector<uint8_t>& stream) {
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

}  // namespace nav::drivers::pd0_test
