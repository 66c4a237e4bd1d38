// Tests of the RDI PD0 decoder on the real recordings in data/dvl: values against the
// *.expected.csv decoded by dolfyn (an independent decoder), byte accounting, re-encoding and
// every-byte splits of real ensembles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "nav/drivers/codecs/pd0.h"
#include "nav/testing/data.h"
#include "pd0_test_support.h"

namespace nav::drivers {
namespace {

using namespace pd0_test;

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

/// A checksum-valid ensemble found in a file: its first byte and its byte count N.
struct ScannedEnsemble {
  std::size_t at = 0;
  std::size_t n = 0;
};

uint16_t le16_at(const std::vector<uint8_t>& bytes, std::size_t i) {
  return uint16_t(bytes[i] | (bytes[i + 1] << 8));
}

/// Independent of the decoder: every 0x7F 0x7F whose byte count N and checksum (sum of the N
/// bytes mod 65536) hold; a valid ensemble's bytes are consumed, as by any decoder.
std::vector<ScannedEnsemble> scan_checksum_valid(const std::vector<uint8_t>& bytes) {
  std::vector<ScannedEnsemble> found;
  std::size_t p = 0;
  while (p + 4 <= bytes.size()) {
    if (bytes[p] == 0x7F && bytes[p + 1] == 0x7F) {
      const std::size_t n = le16_at(bytes, p + 2);
      if (n >= 6 && p + n + 2 <= bytes.size()) {
        uint32_t sum = 0;
        for (std::size_t i = p; i < p + n; ++i) sum += bytes[i];
        if ((sum & 0xFFFF) == le16_at(bytes, p + n)) {
          found.push_back({p, n});
          p += n + 2;
          continue;
        }
      }
    }
    ++p;
  }
  return found;
}

/// The data type IDs of an ensemble in offset-table order.
std::vector<uint16_t> table_ids(const std::vector<uint8_t>& bytes, const ScannedEnsemble& e) {
  std::vector<uint16_t> ids;
  for (std::size_t k = 0; k < bytes[e.at + 5]; ++k) {
    ids.push_back(le16_at(bytes, e.at + le16_at(bytes, e.at + 6 + 2 * k)));
  }
  return ids;
}

/// The IDs a decoder that decodes the first fixed leader, variable leader and bottom track
/// must report as skipped.
std::vector<uint16_t> expected_skipped_ids(const std::vector<uint16_t>& ids) {
  std::vector<uint16_t> skipped;
  bool fixed = false, variable = false, bottom = false;
  for (uint16_t id : ids) {
    bool* first = id == 0x0000   ? &fixed
                  : id == 0x0080 ? &variable
                  : id == 0x0600 ? &bottom
                                 : nullptr;
    if (first && !*first) {
      *first = true;
    } else {
      skipped.push_back(id);
    }
  }
  return skipped;
}

/// IDs outside the WorkHorse PD0 table (leaders, profiles 0x0100..0x0500, bottom track).
std::size_t count_unknown(const std::vector<uint16_t>& ids) {
  return std::size_t(std::count_if(ids.begin(), ids.end(), [](uint16_t id) {
    return id != 0x0000 && id != 0x0080 && !(id >= 0x0100 && id <= 0x0600 && (id & 0xFF) == 0);
  }));
}

TEST(Pd0RealData, WinRiverEveryChecksumValidEnsembleIsDecoded) {
  NAV_REQUIRE_DATA(path, "dvl/winriver01.PD0");
  const std::vector<uint8_t> bytes = read_file(path);
  const std::vector<ScannedEnsemble> scanned = scan_checksum_valid(bytes);
  ASSERT_EQ(scanned.size(), 262u);
  Pd0Decoder decoder;
  std::vector<Pd0Ensemble> out;
  for (std::size_t i = 0; i < bytes.size(); i += 777) {
    decoder.feed({bytes.data() + i, std::min<std::size_t>(777, bytes.size() - i)}, kHost, out);
  }
  ASSERT_EQ(out.size(), scanned.size());
  EXPECT_EQ(decoder.stats().malformed, 0u);
  EXPECT_EQ(decoder.stats().checksum_failures, 0u);
  EXPECT_EQ(decoder.stats().unsupported, 0u);
  EXPECT_EQ(decoder.stats().dropped_bytes, 0u);
  std::size_t skipped = 0, unknown = 0, with_navigation = 0;
  for (std::size_t i = 0; i < scanned.size(); ++i) {
    const std::vector<uint16_t> ids = table_ids(bytes, scanned[i]);
    const std::vector<uint16_t> expected = expected_skipped_ids(ids);
    EXPECT_EQ(out[i].skipped_type_ids, expected) << "ensemble at byte " << scanned[i].at;
    skipped += expected.size();
    unknown += count_unknown(ids);
    with_navigation += std::count(ids.begin(), ids.end(), uint16_t(0x2022)) > 0;
  }
  EXPECT_EQ(with_navigation, 34u);  // WinRiver navigation 0x2022 and NMEA 0x2101 in these
  EXPECT_EQ(decoder.skipped_types().total, skipped);
  EXPECT_EQ(decoder.skipped_types().unknown, unknown);
  EXPECT_EQ(unknown, 2u * 34);
}

/// `ensemble` (header to checksum) with `copies` more copies of `type` (ID and body) appended
/// after its last data type: offset table, byte count and checksum rewritten.
std::vector<uint8_t> with_copies(const std::vector<uint8_t>& ensemble,
                                 const std::vector<uint8_t>& type, std::size_t copies) {
  const std::size_t count = ensemble[5], n = le16_at(ensemble, 2);
  const std::size_t shift = 2 * copies;  // the offset table grows
  std::vector<uint8_t> out(ensemble.begin(), ensemble.begin() + 6);
  out[5] = uint8_t(count + copies);
  const auto put16 = [&out](std::size_t v) {
    out.insert(out.end(), {uint8_t(v), uint8_t(v >> 8)});
  };
  for (std::size_t k = 0; k < count; ++k) put16(le16_at(ensemble, 6 + 2 * k) + shift);
  for (std::size_t j = 0; j < copies; ++j) put16(n + shift + j * type.size());
  out.insert(out.end(), ensemble.begin() + std::ptrdiff_t(6 + 2 * count),
             ensemble.begin() + std::ptrdiff_t(n));
  for (std::size_t j = 0; j < copies; ++j) out.insert(out.end(), type.begin(), type.end());
  out[2] = uint8_t(out.size());
  out[3] = uint8_t(out.size() >> 8);
  out.resize(out.size() + 2);
  fix_checksum(out);
  return out;
}

TEST(Pd0RealData, WinRiverEnsembleWithManyNavigationTypesIsDecoded) {
  // A real WinRiver ensemble (9 types, one GPS fix 0x2022 of 71 bytes) given 26, 59 or 246
  // more copies of its 0x2022 type, as WinRiver writes one per fix: 35, 68 and 255 types.
  NAV_REQUIRE_DATA(path, "dvl/winriver01.PD0");
  const std::vector<uint8_t> bytes = read_file(path);
  const std::vector<ScannedEnsemble> scanned = scan_checksum_valid(bytes);
  std::size_t i = 0;
  while (i < scanned.size() && count_unknown(table_ids(bytes, scanned[i])) == 0) ++i;
  ASSERT_TRUE(i > 0 && i + 1 < scanned.size());
  const auto slice = [&bytes](const ScannedEnsemble& e) {
    return std::vector<uint8_t>(bytes.begin() + std::ptrdiff_t(e.at),
                                bytes.begin() + std::ptrdiff_t(e.at + e.n + 2));
  };
  const std::vector<uint8_t> original = slice(scanned[i]);
  const std::vector<uint16_t> ids = table_ids(bytes, scanned[i]);
  ASSERT_EQ(ids.size(), 9u);
  ASSERT_EQ(ids[7], 0x2022);  // located by its offset and the next one
  const std::size_t nav_at = le16_at(original, 6 + 2 * 7), nav_end = le16_at(original, 6 + 2 * 8);
  const std::vector<uint8_t> navigation(original.begin() + std::ptrdiff_t(nav_at),
                                        original.begin() + std::ptrdiff_t(nav_end));
  ASSERT_EQ(navigation.size(), 71u);
  Pd0Decoder reference_decoder;
  const auto reference = decode_all(original, reference_decoder);
  ASSERT_EQ(reference.size(), 1u);

  for (const std::size_t types : {35u, 68u, 255u}) {
    SCOPED_TRACE(::testing::Message() << types << " data types");
    const std::vector<uint8_t> many = with_copies(original, navigation, types - ids.size());
    ASSERT_EQ(many[5], types);
    std::vector<uint8_t> stream = slice(scanned[i - 1]);  // between its real neighbours
    append(stream, many);
    append(stream, slice(scanned[i + 1]));
    Pd0Decoder decoder;
    const auto out = decode_all(stream, decoder);
    ASSERT_EQ(out.size(), 3u);
    EXPECT_EQ(decoder.stats().malformed, 0u);
    EXPECT_EQ(decoder.stats().dropped_bytes, 0u);
    expect_same(out[1], reference[0]);
    std::vector<uint16_t> expected = reference[0].skipped_type_ids;
    expected.insert(expected.end(), types - ids.size(), uint16_t(0x2022));
    EXPECT_EQ(out[1].skipped_type_ids, expected);
    EXPECT_EQ(decoder.skipped_types().unknown, count_unknown(table_ids(bytes, scanned[i - 1])) + 2 +
                                                   (types - ids.size()) +
                                                   count_unknown(table_ids(bytes, scanned[i + 1])));
  }
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
