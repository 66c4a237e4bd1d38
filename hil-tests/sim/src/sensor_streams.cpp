#include "nav/sim/sensor_streams.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "nav/core/geometry/rotation.h"
#include "nav/drivers/codecs/altimeter.h"
#include "nav/drivers/codecs/nmea.h"
#include "nav/drivers/codecs/paroscientific.h"
#include "nav/drivers/codecs/pd0.h"
#include "nav/drivers/codecs/seawater.h"

namespace nav::sim {
namespace {

constexpr std::int64_t kDvlPeriodUs = 200000;        // 5 Hz
constexpr std::int64_t kHeadingPeriodUs = 100000;    // 10 Hz
constexpr std::int64_t kDepthPeriodUs = 500000;      // 2 Hz
constexpr std::int64_t kAltimeterPeriodUs = 200000;  // 5 Hz
constexpr std::int64_t kAltimeterOffsetUs = 100000;  // altimeter pings between DVL pings
constexpr std::int64_t kDepthOffsetUs = 250000;
constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kBeamAngleRad = 30.0 * std::numbers::pi / 180.0;

bool due(std::int64_t t_us, std::int64_t period_us, std::int64_t offset_us) {
  return (t_us - kDiveStartMonotonicUs - offset_us) % period_us == 0 &&
         t_us - kDiveStartMonotonicUs >= offset_us;
}

core::Mat3 mount_rotation(const daemon::Mount& m) {
  return core::rotation_from_euler(core::Vec3(m.rpy_rad[0], m.rpy_rad[1], m.rpy_rad[2]));
}
core::Vec3 lever_arm(const daemon::Mount& m) {
  return core::Vec3(m.lever_arm_m[0], m.lever_arm_m[1], m.lever_arm_m[2]);
}

std::vector<std::uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

const daemon::SensorConfig& require_sensor(const daemon::NavdConfig& c, daemon::SensorType t) {
  const daemon::SensorConfig* s = find_sensor(c, t);
  if (!s)
    throw std::invalid_argument(std::string("simulator: the config has no sensor of type ") +
                                daemon::to_string(t));
  return *s;
}

}  // namespace

SensorErrorOptions SensorErrorOptions::with_sensor_biases() {
  SensorErrorOptions o;
  o.dvl_scale_error = 0.001;
  o.heading_bias_rad = 0.05 * std::numbers::pi / 180.0;
  o.roll_pitch_bias_rad = 0.02 * std::numbers::pi / 180.0;
  o.depth_bias_m = 0.02;
  return o;
}

SensorErrorOptions SensorErrorOptions::ideal() {
  SensorErrorOptions o;
  o.dvl_scale_error = 0.0;
  o.heading_bias_rad = 0.0;
  o.roll_pitch_bias_rad = 0.0;
  o.depth_bias_m = 0.0;
  o.altitude_bias_m = 0.0;
  o.dvl_clock_offset_s = 0.0;
  o.dvl_clock_drift_ppm = 0.0;
  o.dvl_dropouts_per_hour = 0.0;
  return o;
}

std::string SensorErrorOptions::validate() const {
  auto finite = [](double v) { return std::isfinite(v); };
  if (!finite(dvl_scale_error) || std::abs(dvl_scale_error) > 0.1)
    return "dvl_scale_error: outside [-0.1, 0.1]";
  for (double b : {heading_bias_rad, roll_pitch_bias_rad})
    if (!finite(b) || std::abs(b) > 0.2)
      return "heading/roll_pitch_bias_rad: outside [-0.2, 0.2] rad";
  if (!finite(depth_bias_m) || !finite(altitude_bias_m)) return "depth/altitude_bias_m: not finite";
  if (!finite(dvl_clock_offset_s) || !finite(dvl_clock_drift_ppm))
    return "dvl_clock_offset_s/drift_ppm: not finite";
  if (!(dvl_dropouts_per_hour >= 0.0 && dvl_dropouts_per_hour <= 100.0))
    return "dvl_dropouts_per_hour: outside [0, 100]";
  if (!(dvl_dropout_min_s > 0.0 && dvl_dropout_min_s <= dvl_dropout_max_s &&
        dvl_dropout_max_s <= 3600.0))
    return "dvl_dropout_min_s/max_s: need 0 < min <= max <= 3600 s";
  if (!(jitter_ms >= 0.0 && jitter_ms <= 1000.0)) return "jitter_ms: outside [0, 1000]";
  if (!(serial_baud >= 300.0)) return "serial_baud: below 300";
  return "";
}

std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

const daemon::SensorConfig* find_sensor(const daemon::NavdConfig& c, daemon::SensorType t) {
  for (const daemon::SensorConfig& s : c.sensors)
    if (s.type == t) return &s;
  return nullptr;
}

double unesco1983_sea_pressure_dbar(double depth_m, double latitude_rad) {
  double p = depth_m / 0.9945;  // ~1.0055 dbar per metre at mid depths
  for (int i = 0; i < 20; ++i) {
    const double f = drivers::unesco1983_depth_m(p, latitude_rad) - depth_m;
    const double dfdp = (drivers::unesco1983_depth_m(p + 0.01, latitude_rad) -
                         drivers::unesco1983_depth_m(p - 0.01, latitude_rad)) /
                        0.02;
    p -= f / dfdp;
    if (std::abs(f) < 1e-10) break;
  }
  return p;
}

SensorStreams::SensorStreams(const daemon::NavdConfig& config, const SensorErrorOptions& errors,
                             const Seafloor& seafloor, double dive_duration_s, std::uint64_t seed)
    : errors_(errors), seafloor_(&seafloor) {
  dvl_ = {&require_sensor(config, daemon::SensorType::kDvlPd0),
          std::mt19937_64(derive_seed(seed, 11))};
  heading_ = {&require_sensor(config, daemon::SensorType::kHeadingNmea),
              std::mt19937_64(derive_seed(seed, 12))};
  depth_ = {&require_sensor(config, daemon::SensorType::kPressureParo),
            std::mt19937_64(derive_seed(seed, 13))};
  altimeter_ = {&require_sensor(config, daemon::SensorType::kAltimeter),
                std::mt19937_64(derive_seed(seed, 14))};
  // Bottom-lock losses: spread over the dive, one per equal share, away from the start.
  std::mt19937_64 rng(derive_seed(seed, 15));
  const int n = errors.dvl_dropouts_per_hour <= 0.0
                    ? 0
                    : std::max(1, static_cast<int>(std::lround(errors.dvl_dropouts_per_hour *
                                                               dive_duration_s / 3600.0)));
  for (int i = 0; i < n; ++i) {
    const double share = dive_duration_s / n;
    std::uniform_real_distribution<double> len(errors.dvl_dropout_min_s, errors.dvl_dropout_max_s);
    const double length = len(rng);
    std::uniform_real_distribution<double> at(0.2 * share,
                                              std::max(0.2 * share, 0.9 * share - length));
    const double start = i * share + at(rng);
    dropouts_.push_back({start, start + length});
  }
}

double SensorStreams::gauss(Stream& s, double sigma) {
  return sigma * std::normal_distribution<double>(0.0, 1.0)(s.rng);
}

std::int64_t SensorStreams::host_time(Stream& s, std::int64_t t_us) {
  const double jitter_us =
      std::uniform_real_distribution<double>(0.0, errors_.jitter_ms * 1000.0)(s.rng);
  return t_us + std::llround(s.config->latency_s * 1e6 + jitter_us);
}

std::int64_t SensorStreams::dvl_clock_us(std::int64_t t_us) const {
  const double since_start_s = (t_us - kDiveStartMonotonicUs) * 1e-6;
  const double clock_error_s =
      errors_.dvl_clock_offset_s + errors_.dvl_clock_drift_ppm * 1e-6 * since_start_s;
  return realtime_of(t_us) + std::llround(clock_error_s * 1e6);
}

void SensorStreams::sample(std::int64_t t_us, const core::Vec12& x, std::vector<RawEvent>& out) {
  if (due(t_us, kDvlPeriodUs, 0)) sample_dvl(t_us, x, out);
  if (due(t_us, kHeadingPeriodUs, 0)) sample_heading(t_us, x, out);
  if (due(t_us, kDepthPeriodUs, kDepthOffsetUs)) sample_depth(t_us, x, out);
  if (due(t_us, kAltimeterPeriodUs, kAltimeterOffsetUs)) sample_altimeter(t_us, x, out);
}

void SensorStreams::sample_dvl(std::int64_t t_us, const core::Vec12& x,
                               std::vector<RawEvent>& out) {
  const daemon::SensorConfig& cfg = *dvl_.config;
  const core::Mat3 R_world_body = core::rotation_from_euler(x.segment<3>(3));
  const core::Mat3 R_body_dvl = mount_rotation(cfg.mount);
  const core::Vec3 lever = lever_arm(cfg.mount);
  // Velocity over ground of the DVL's own location, in the DVL (instrument) frame.
  const core::Vec3 v_dvl =
      R_body_dvl.transpose() * (x.segment<3>(6) + x.segment<3>(9).cross(lever));
  const core::Vec3 p_dvl = x.head<3>() + R_world_body * lever;

  drivers::Pd0Ensemble e;
  e.time.sensor_time_us = dvl_clock_us(t_us);
  e.ensemble_number = ++ensemble_number_;
  e.fixed.firmware_version = 51;
  e.fixed.firmware_revision = 40;
  e.fixed.system_config = 0x4A8B;  // 600 kHz, Janus convex, 30 deg, down-looking
  e.fixed.num_beams = 4;
  e.fixed.num_cells = 0;
  e.fixed.pings_per_ensemble = 1;
  e.fixed.coord_transform = 0x08;  // instrument coordinates (EX01000)
  e.fixed.sensor_source = 0x7D;
  e.fixed.sensors_available = 0x3D;
  e.fixed.serial_number = 4711;
  e.fixed.beam_angle_deg = 30;
  e.temperature_c = 1.5;
  e.salinity_ppt = 35.0;
  e.sound_speed_mps = 1500.0;
  e.depth_m = p_dvl.z();
  // The DVL's own compass and tilt sensors (not used by navd): the instrument's attitude with
  // a compass error of ~1 deg and tilt errors of ~0.2 deg.
  const core::Vec3 rpy_dvl = core::euler_from_rotation(R_world_body * R_body_dvl);
  e.heading_rad = std::fmod(rpy_dvl[2] + gauss(dvl_, 1.0 * kDegToRad) + 4.0 * std::numbers::pi,
                            2.0 * std::numbers::pi);
  e.pitch_rad = rpy_dvl[1] + gauss(dvl_, 0.2 * kDegToRad);
  e.roll_rad = rpy_dvl[0] + gauss(dvl_, 0.2 * kDegToRad);
  e.pressure_dbar = unesco1983_sea_pressure_dbar(
      p_dvl.z(), depth_.config->pressure.latitude_deg * std::numbers::pi / 180.0);

  drivers::Pd0BottomTrack bt;
  bt.pings_per_ensemble = 1;
  const double t_s = (t_us - kDiveStartMonotonicUs) * 1e-6;
  const bool locked = std::none_of(dropouts_.begin(), dropouts_.end(),
                                   [&](const auto& d) { return t_s >= d.first && t_s < d.second; });
  ++counts_.dvl_ensembles;
  const double sigma = cfg.noise.velocity_mps;
  const double scale = 1.0 + errors_.dvl_scale_error;
  // Draw the noise whether or not the bottom is tracked, so dropouts do not shift the stream.
  const core::Vec3 noise(gauss(dvl_, sigma), gauss(dvl_, sigma), gauss(dvl_, sigma));
  const double error_velocity = gauss(dvl_, 0.3 * sigma);
  if (locked) {
    // PD0 bottom track is the bottom relative to the instrument: minus the DVL's velocity.
    for (int i = 0; i < 3; ++i)
      bt.velocity_mps[static_cast<std::size_t>(i)] = -(scale * v_dvl[i] + noise[i]);
    bt.velocity_mps[3] = error_velocity;
    const core::Mat3 R_world_dvl = R_world_body * R_body_dvl;
    for (int b = 0; b < 4; ++b) {  // vertical range below each beam's spot on the seafloor
      const double az = b * std::numbers::pi / 2.0;
      const core::Vec3 dir_world =
          R_world_dvl * core::Vec3(std::sin(kBeamAngleRad) * std::cos(az),
                                   std::sin(kBeamAngleRad) * std::sin(az), std::cos(kBeamAngleRad));
      const double guess = seafloor_->depth_m(p_dvl.x(), p_dvl.y()) - p_dvl.z();
      const double reach = guess / std::max(0.3, dir_world.z());
      const double floor =
          seafloor_->depth_m(p_dvl.x() + reach * dir_world.x(), p_dvl.y() + reach * dir_world.y());
      bt.range_m[static_cast<std::size_t>(b)] = std::max(0.5, floor - p_dvl.z());
      bt.correlation[static_cast<std::size_t>(b)] = 230;
      bt.eval_amplitude[static_cast<std::size_t>(b)] = 160;
      bt.percent_good[static_cast<std::size_t>(b)] = 100;
    }
  } else {
    ++counts_.dvl_invalid_ensembles;
  }
  e.bottom_track = bt;
  out.push_back({host_time(dvl_, t_us), cfg.name, drivers::encode_pd0(e)});
}

void SensorStreams::sample_heading(std::int64_t t_us, const core::Vec12& x,
                                   std::vector<RawEvent>& out) {
  const daemon::SensorConfig& cfg = *heading_.config;
  // The Octans is aligned with the body (its mount rotation is taken into account if set).
  const core::Mat3 R_world_sensor =
      core::rotation_from_euler(x.segment<3>(3)) * mount_rotation(cfg.mount);
  const core::Vec3 rpy = core::euler_from_rotation(R_world_sensor);
  drivers::NmeaHeading h;
  h.heading_rad =
      core::wrap_angle(rpy[2] + errors_.heading_bias_rad + gauss(heading_, cfg.noise.heading_rad));
  drivers::NmeaAttitude a;
  a.roll_rad = rpy[0] + errors_.roll_pitch_bias_rad + gauss(heading_, cfg.noise.roll_pitch_rad);
  a.pitch_rad = rpy[1] + errors_.roll_pitch_bias_rad + gauss(heading_, cfg.noise.roll_pitch_rad);
  const std::string hdt = drivers::encode_nmea(h);
  const std::string phtro = drivers::encode_nmea(a);
  const std::int64_t host = host_time(heading_, t_us);
  out.push_back({host, cfg.name, bytes_of(hdt)});
  // The second sentence follows the first on the line (10 bits per character).
  const std::int64_t gap_us = std::llround(phtro.size() * 10.0 / errors_.serial_baud * 1e6);
  out.push_back({host + gap_us, cfg.name, bytes_of(phtro)});
  ++counts_.heading_sentences;
  ++counts_.attitude_sentences;
}

void SensorStreams::sample_depth(std::int64_t t_us, const core::Vec12& x,
                                 std::vector<RawEvent>& out) {
  const daemon::SensorConfig& cfg = *depth_.config;
  const core::Vec3 p =
      x.head<3>() + core::rotation_from_euler(x.segment<3>(3)) * lever_arm(cfg.mount);
  const double depth = p.z() + errors_.depth_bias_m + gauss(depth_, cfg.noise.depth_m);
  const double lat_rad = cfg.pressure.latitude_deg * std::numbers::pi / 180.0;
  drivers::ParoRecord r;
  r.destination_id = 0;
  r.source_id = 1;
  r.pressure_pa =
      (unesco1983_sea_pressure_dbar(depth, lat_rad) + cfg.pressure.surface_pressure_dbar) *
      drivers::kPascalPerDecibar;
  out.push_back(
      {host_time(depth_, t_us), cfg.name, bytes_of(drivers::encode_paro_reply(r, {}, 4))});
  ++counts_.depth_replies;
}

void SensorStreams::sample_altimeter(std::int64_t t_us, const core::Vec12& x,
                                     std::vector<RawEvent>& out) {
  const daemon::SensorConfig& cfg = *altimeter_.config;
  const core::Mat3 R_world_body = core::rotation_from_euler(x.segment<3>(3));
  const core::Vec3 p = x.head<3>() + R_world_body * lever_arm(cfg.mount);
  // Range along the sensor's z axis (down in the body unless mounted otherwise) to the height
  // field: fixed point from the seafloor straight below.
  const core::Vec3 axis = R_world_body * mount_rotation(cfg.mount) * core::Vec3::UnitZ();
  double range = seafloor_->depth_m(p.x(), p.y()) - p.z();
  if (axis.z() > 0.2) {
    for (int k = 0; k < 4; ++k) {
      const core::Vec3 q = p + (range / axis.z()) * axis;
      range = seafloor_->depth_m(q.x(), q.y()) - p.z();
    }
    range /= axis.z();
  }
  drivers::AltimeterRecord r;
  r.raw_value_m =
      std::max(0.1, range + errors_.altitude_bias_m + gauss(altimeter_, cfg.noise.altitude_m));
  out.push_back({host_time(altimeter_, t_us), cfg.name, bytes_of(drivers::encode_altimeter(r))});
  ++counts_.altimeter_lines;
}

}  // namespace nav::sim
