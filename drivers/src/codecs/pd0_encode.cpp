// PD0 encoder: header, fixed leader (59 bytes), variable leader (65 bytes) and bottom track
// (85 bytes) in the layout of "WorkHorse Commands and Output Data Format", PD0 Output Format,
// then any extra data types verbatim. Used by tests, fuzzers and the survey simulator; fields
// it does not model are written 0.
#include <algorithm>
#include <climits>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "nav/drivers/codecs/pd0.h"
#include "pd0_wire.h"

namespace nav::drivers {
namespace {

using namespace pd0_wire;

constexpr double kRadToCentiDeg = 18000.0 / std::numbers::pi;

/// Rounds to the nearest integer and clamps to [lo, hi].
int64_t quantize(double value, double scale, int64_t lo, int64_t hi) {
  const double q = std::round(value / scale);
  if (!(q >= double(lo))) return lo;  // also NaN
  if (q > double(hi)) return hi;
  return int64_t(q);
}

void write_fixed(uint8_t* p, const Pd0FixedLeader& f) {
  put16(p, kFixedLeaderId);
  p[2] = f.firmware_version;
  p[3] = f.firmware_revision;
  put16(p + 4, f.system_config);
  p[8] = f.num_beams;
  p[9] = f.num_cells;
  put16(p + 10, f.pings_per_ensemble);
  put16(p + 12, uint16_t(quantize(f.cell_length_m, 0.01, 0, 0xFFFF)));
  put16(p + 14, uint16_t(quantize(f.blank_m, 0.01, 0, 0xFFFF)));
  p[25] = f.coord_transform;
  p[30] = f.sensor_source;
  p[31] = f.sensors_available;
  put16(p + 32, uint16_t(quantize(f.bin1_distance_m, 0.01, 0, 0xFFFF)));
  put32(p + 54, f.serial_number);
  p[58] = f.beam_angle_deg;
}

void write_time(uint8_t* p, const std::optional<int64_t>& time_us) {
  if (!time_us) return;  // all-zero RTC: month 0 decodes as "no time"
  const CivilTime t = unix_us_to_civil(*time_us);
  const uint8_t fields[7] = {uint8_t(t.year % 100), uint8_t(t.month),  uint8_t(t.day),
                             uint8_t(t.hour),       uint8_t(t.minute), uint8_t(t.second),
                             uint8_t(t.hundredths)};
  for (int i = 0; i < 7; ++i) p[4 + i] = fields[i];   // 5-11
  p[57] = uint8_t(t.year / 100);                      // 58 century
  for (int i = 0; i < 7; ++i) p[58 + i] = fields[i];  // 59-65
}

void write_variable(uint8_t* p, const Pd0Ensemble& e) {
  put16(p, kVariableLeaderId);
  put16(p + 2, uint16_t(e.ensemble_number & 0xFFFF));
  p[11] = uint8_t((e.ensemble_number >> 16) & 0xFF);
  write_time(p, e.time.sensor_time_us);
  put16(p + 12, e.bit_result);
  // Empty values are written out of range (no PD0 marker exists) so they decode empty again.
  put16(p + 14, e.sound_speed_mps ? uint16_t(quantize(*e.sound_speed_mps, 1, 0, 0xFFFF)) : 0);
  put16(p + 16, uint16_t(quantize(e.depth_m.value_or(0.0), 0.1, 0, 0xFFFF)));
  if (e.heading_rad) {
    const double wrapped =
        std::fmod(std::fmod(*e.heading_rad, 2 * std::numbers::pi) + 2 * std::numbers::pi,
                  2 * std::numbers::pi);
    const int64_t centideg = quantize(wrapped, 1 / kRadToCentiDeg, 0, 36000);
    put16(p + 18, uint16_t(centideg == 36000 ? 0 : centideg));
  } else {
    put16(p + 18, 0xFFFF);
  }
  const auto centideg = [](const std::optional<double>& a) {
    return a ? uint16_t(int16_t(quantize(*a, 1 / kRadToCentiDeg, -9000, 9000))) : uint16_t(0x8000);
  };
  put16(p + 20, centideg(e.pitch_rad));
  put16(p + 22, centideg(e.roll_rad));
  put16(p + 24, e.salinity_ppt ? uint16_t(quantize(*e.salinity_ppt, 1, 0, 0xFFFF)) : 0xFFFF);
  put16(p + 26, e.temperature_c ? uint16_t(int16_t(quantize(*e.temperature_c, 0.01, -32767, 32767)))
                                : uint16_t(0x8000));
  put32(p + 48,
        uint32_t(int32_t(quantize(e.pressure_dbar.value_or(0.0), 0.001, INT32_MIN, INT32_MAX))));
}

void write_bottom_track(uint8_t* p, const Pd0BottomTrack& bt) {
  put16(p, kBottomTrackId);
  put16(p + 2, bt.pings_per_ensemble);
  for (int b = 0; b < 4; ++b) {
    const uint32_t range_cm =
        bt.range_m[b] ? uint32_t(quantize(*bt.range_m[b], 0.01, 0, 0xFFFFFF)) : 0;
    put16(p + 16 + 2 * b, uint16_t(range_cm & 0xFFFF));
    p[77 + b] = uint8_t(range_cm >> 16);
    const int16_t v = bt.velocity_mps[b]
                          ? int16_t(quantize(*bt.velocity_mps[b], 0.001, -32767, 32767))
                          : kInvalidVelocity;
    put16(p + 24 + 2 * b, uint16_t(v));
    p[32 + b] = bt.correlation[b];
    p[36 + b] = bt.eval_amplitude[b];
    p[40 + b] = bt.percent_good[b];
  }
}

}  // namespace

std::vector<uint8_t> encode_pd0(const Pd0Ensemble& e) { return encode_pd0(e, {}); }

std::vector<uint8_t> encode_pd0(const Pd0Ensemble& e, std::span<const Pd0RawDataType> extra) {
  const std::size_t decoded = e.bottom_track ? 3 : 2;
  const std::size_t types = decoded + extra.size();
  if (types > kMaxDataTypes) {
    throw std::invalid_argument("encode_pd0: " + std::to_string(types) +
                                " data types; the PD0 header's count holds at most 255");
  }
  std::vector<std::size_t> offsets(types);
  std::size_t at = kHeaderFixedBytes + 2 * types;  // the first type follows the offset table
  const std::size_t sizes[3] = {kFixedLeaderBytes, kVariableLeaderBytes, kBottomTrackBytes};
  for (std::size_t k = 0; k < decoded; ++k) {
    offsets[k] = at;
    at += sizes[k];
  }
  for (std::size_t k = 0; k < extra.size(); ++k) {
    if (extra[k].id == kBottomTrackId && !e.bottom_track) {
      throw std::invalid_argument("encode_pd0: extra data type " + std::to_string(k) +
                                  " has the bottom-track ID 0x0600 but the ensemble has no "
                                  "bottom track; it would be decoded as the bottom track");
    }
    offsets[decoded + k] = at;
    at += 2 + extra[k].body.size();
  }
  const std::size_t n = at;
  if (n > 0xFFFF) {
    throw std::invalid_argument("encode_pd0: ensemble of " + std::to_string(n) +
                                " bytes before the checksum; the PD0 byte count holds at most "
                                "65535");
  }
  std::vector<uint8_t> out(n + kChecksumBytes, 0);
  uint8_t* p = out.data();
  p[0] = kHeaderId;
  p[1] = kHeaderId;
  put16(p + 2, uint16_t(n));
  p[5] = uint8_t(types);
  for (std::size_t k = 0; k < types; ++k) {
    put16(p + kHeaderFixedBytes + 2 * k, uint16_t(offsets[k]));
  }
  write_fixed(p + offsets[0], e.fixed);
  write_variable(p + offsets[1], e);
  if (e.bottom_track) write_bottom_track(p + offsets[2], *e.bottom_track);
  for (std::size_t k = 0; k < extra.size(); ++k) {
    uint8_t* t = p + offsets[decoded + k];
    put16(t, extra[k].id);
    std::copy(extra[k].body.begin(), extra[k].body.end(), t + 2);
  }
  put16(p + n, pd0_checksum({p, n}));
  return out;
}

}  // namespace nav::drivers
