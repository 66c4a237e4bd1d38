// Decoding of one complete PD0 ensemble: offset table, fixed leader, variable leader and
// bottom track ("WorkHorse Commands and Output Data Format", PD0 Output Format: "Header Data
// Format", "Fixed Leader Data Format", "Variable Leader Data Format", "Bottom-Track Data
// Format"). Byte positions in comments are the manual's 1-based positions within the type.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>

#include "nav/drivers/codecs/pd0.h"
#include "pd0_wire.h"

namespace nav::drivers {
namespace {

using namespace pd0_wire;

constexpr double kCentiDegToRad = std::numbers::pi / 18000.0;

// Documented ranges (manual's command descriptions) used to reject absurd values.
constexpr double kMinTemperatureC = -10.0;  // ET accepts -5..40 degC; sensor margin either side
constexpr double kMaxTemperatureC = 50.0;
constexpr double kMaxSalinityPpt = 40.0;      // ES: 0..40
constexpr double kMinSoundSpeedMps = 1400.0;  // EC: 1400..1600
constexpr double kMaxSoundSpeedMps = 1600.0;
constexpr double kMinPressureDbar = -10.0;    // sensor offset at the surface
constexpr double kMaxPressureDbar = 12000.0;  // deeper than any ocean
constexpr double kMaxBtVelocityMps = 20.0;    // far beyond any DVL's bottom-track limit
constexpr double kMaxBtRangeM = 2000.0;       // beyond the longest-range bottom track

struct DataType {
  uint16_t id = 0;
  const uint8_t* data = nullptr;
  std::size_t size = 0;  ///< bytes up to the next data type (or the checksum)
};

/// The offset table of one ensemble, held without allocation (at most 255 entries).
struct OffsetTable {
  std::size_t n = 0;                              ///< ensemble byte count (excluding the checksum)
  std::size_t count = 0;                          ///< number of data types
  std::array<uint16_t, kMaxDataTypes> offsets{};  ///< in table order
  std::array<uint16_t, kMaxDataTypes> sorted{};   ///< ascending, for the extents
};

/// Reads the offset table: every offset inside the table's end .. N - 2, no two equal.
bool read_offsets(std::span<const uint8_t> e, OffsetTable& table) {
  if (e.size() < kHeaderFixedBytes + kChecksumBytes) return false;
  table.n = le16(&e[2]);
  table.count = e[5];
  const std::size_t table_end = kHeaderFixedBytes + 2 * table.count;
  if (table.count == 0 || table.n + kChecksumBytes != e.size() || table_end + 2 > table.n) {
    return false;
  }
  for (std::size_t i = 0; i < table.count; ++i) {
    const uint16_t offset = le16(&e[kHeaderFixedBytes + 2 * i]);
    if (offset < table_end || offset + 2u > table.n) return false;
    table.offsets[i] = table.sorted[i] = offset;
  }
  const auto sorted_end = table.sorted.begin() + std::ptrdiff_t(table.count);
  std::sort(table.sorted.begin(), sorted_end);
  return std::adjacent_find(table.sorted.begin(), sorted_end) == sorted_end;
}

/// The k-th data type in table order; its extent runs to the next higher offset or to N.
DataType type_at(std::span<const uint8_t> e, const OffsetTable& table, std::size_t k) {
  const std::size_t offset = table.offsets[k];
  const auto sorted_end = table.sorted.begin() + std::ptrdiff_t(table.count);
  const auto next = std::upper_bound(table.sorted.begin(), sorted_end, offset);
  const std::size_t end = next == sorted_end ? table.n : *next;
  return {le16(&e[offset]), &e[offset], end - offset};
}

/// Keeps `value` when lo <= value <= hi, else counts a rejected field.
std::optional<double> in_range(double value, double lo, double hi, int& rejected) {
  if (value >= lo && value <= hi) return value;
  ++rejected;
  return std::nullopt;
}

void parse_fixed(const DataType& t, Pd0FixedLeader& f) {
  const uint8_t* p = t.data;
  f.firmware_version = p[2];                          // 3
  f.firmware_revision = p[3];                         // 4
  f.system_config = le16(p + 4);                      // 5-6
  f.num_beams = p[8];                                 // 9
  f.num_cells = p[9];                                 // 10
  f.pings_per_ensemble = le16(p + 10);                // 11-12 (WP)
  f.cell_length_m = le16(p + 12) * 0.01;              // 13-14 (WS), cm
  f.blank_m = le16(p + 14) * 0.01;                    // 15-16 (WF), cm
  f.coord_transform = p[25];                          // 26 (EX)
  f.sensor_source = p[30];                            // 31 (EZ)
  f.sensors_available = p[31];                        // 32
  f.bin1_distance_m = le16(p + 32) * 0.01;            // 33-34, cm
  f.serial_number = t.size >= 58 ? le32(p + 54) : 0;  // 55-58
  f.beam_angle_deg = t.size >= 59 ? p[58] : 0;        // 59
}

std::optional<int64_t> rtc_time(const DataType& t) {
  const uint8_t* p = t.data;
  if (t.size >= kVariableY2kBytes && (p[57] == 19 || p[57] == 20)) {  // 58-65 Y2K RTC
    return civil_to_unix_us({p[57] * 100 + p[58], p[59], p[60], p[61], p[62], p[63], p[64]});
  }
  const int yy = p[4];  // 5-11: 2-digit year RTC
  if (yy > 99) return std::nullopt;
  const int year = yy >= 80 ? 1900 + yy : 2000 + yy;
  return civil_to_unix_us({year, p[5], p[6], p[7], p[8], p[9], p[10]});
}

void parse_variable(const DataType& t, Pd0Ensemble& e, int& rejected) {
  const uint8_t* p = t.data;
  e.ensemble_number = le16(p + 2) + (uint32_t(p[11]) << 16);  // 3-4, MSB 12
  e.time.sensor_time_us = rtc_time(t);
  if (!e.time.sensor_time_us) ++rejected;
  e.bit_result = le16(p + 12);  // 13-14
  e.sound_speed_mps =
      in_range(le16(p + 14), kMinSoundSpeedMps, kMaxSoundSpeedMps, rejected);  // 15-16
  e.depth_m = le16(p + 16) * 0.1;                                              // 17-18, dm
  const uint16_t heading = le16(p + 18);                                       // 19-20
  if (heading < 36000) {
    e.heading_rad = heading * kCentiDegToRad;
  } else {
    ++rejected;
  }
  const double half_pi = std::numbers::pi / 2;
  e.pitch_rad = in_range(le16s(p + 20) * kCentiDegToRad, -half_pi, half_pi, rejected);  // 21-22
  e.roll_rad = in_range(le16s(p + 22) * kCentiDegToRad, -half_pi, half_pi, rejected);   // 23-24
  e.salinity_ppt = in_range(le16(p + 24), 0.0, kMaxSalinityPpt, rejected);              // 25-26
  e.temperature_c =
      in_range(le16s(p + 26) * 0.01, kMinTemperatureC, kMaxTemperatureC, rejected);  // 27-28
  if (t.size >= kVariablePressureBytes) {
    // 49-52, daPa. The manual lists it unsigned, but instruments at the surface report small
    // negative offsets in two's complement (e.g. -7 daPa in RDI_withBT.000): read signed.
    const double dbar = int32_t(le32(p + 48)) * 0.001;
    e.pressure_dbar = in_range(dbar, kMinPressureDbar, kMaxPressureDbar, rejected);
  }
}

Pd0BottomTrack parse_bottom_track(const DataType& t, int& rejected) {
  const uint8_t* p = t.data;
  Pd0BottomTrack bt;
  bt.pings_per_ensemble = le16(p + 2);  // 3-4 (BP)
  const bool has_msb = t.size >= kBottomTrackMsbBytes;
  for (int b = 0; b < 4; ++b) {
    const uint32_t range_cm =
        le16(p + 16 + 2 * b) + (has_msb ? uint32_t(p[77 + b]) << 16 : 0);  // 17-24, 78-81
    if (range_cm != 0) bt.range_m[b] = in_range(range_cm * 0.01, 0.0, kMaxBtRangeM, rejected);
    const int16_t v = le16s(p + 24 + 2 * b);  // 25-32, mm/s
    if (v != kInvalidVelocity) {
      bt.velocity_mps[b] = in_range(v * 0.001, -kMaxBtVelocityMps, kMaxBtVelocityMps, rejected);
    }
    bt.correlation[b] = p[32 + b];     // 33-36
    bt.eval_amplitude[b] = p[36 + b];  // 37-40
    bt.percent_good[b] = p[40 + b];    // 41-44
  }
  return bt;
}

}  // namespace

const char* to_string(Pd0CoordFrame frame) {
  switch (frame) {
    case Pd0CoordFrame::kBeam:
      return "beam";
    case Pd0CoordFrame::kInstrument:
      return "instrument";
    case Pd0CoordFrame::kShip:
      return "ship";
    case Pd0CoordFrame::kEarth:
      return "earth";
  }
  return "unknown";
}

bool Pd0BottomTrack::velocity_valid() const {
  return std::all_of(velocity_mps.begin(), velocity_mps.end(),
                     [](const auto& v) { return v.has_value(); });
}

uint16_t pd0_checksum(std::span<const uint8_t> bytes) {
  uint32_t sum = 0;
  for (uint8_t b : bytes) sum += b;
  return uint16_t(sum & 0xFFFF);
}

Pd0ParseError parse_pd0_ensemble(std::span<const uint8_t> ensemble, Pd0Ensemble& out,
                                 int& out_of_range_fields) {
  out_of_range_fields = 0;
  OffsetTable table;
  if (!read_offsets(ensemble, table)) return Pd0ParseError::kMalformed;
  std::optional<DataType> fixed, variable, bottom;
  out = Pd0Ensemble{};
  if (table.count > 3) out.skipped_type_ids.reserve(table.count);  // one allocation at most
  for (std::size_t k = 0; k < table.count; ++k) {
    const DataType t = type_at(ensemble, table, k);
    if (t.id == kFixedLeaderId && !fixed) {
      fixed = t;
    } else if (t.id == kVariableLeaderId && !variable) {
      variable = t;
    } else if (t.id == kBottomTrackId && !bottom) {
      bottom = t;
    } else {
      out.skipped_type_ids.push_back(t.id);
    }
  }
  if (!fixed || !variable) return Pd0ParseError::kUnsupported;
  if (fixed->size < kFixedLeaderMinBytes || variable->size < kVariableLeaderMinBytes ||
      (bottom && bottom->size < kBottomTrackMinBytes)) {
    return Pd0ParseError::kMalformed;
  }
  parse_fixed(*fixed, out.fixed);
  parse_variable(*variable, out, out_of_range_fields);
  if (bottom) out.bottom_track = parse_bottom_track(*bottom, out_of_range_fields);
  return out_of_range_fields > 0 ? Pd0ParseError::kOutOfRange : Pd0ParseError::kNone;
}

}  // namespace nav::drivers
