#pragma once
// A small synthetic dive for NavFilter tests: a vehicle on a circle (constant body velocity
// and yaw rate: the filter's constant-velocity model holds exactly) at constant depth and
// altitude, seen through config/sim.yaml's sensors with their mounts and noise (DVL 5 Hz in
// the DVL frame, Octans heading-only and roll/pitch-only messages 5 Hz, depth and altitude 1 Hz,
// an image every image_period_s; the first tick has every sensor, so the filter initialises
// there, at the world origin), and oracle registrations of every image pair whose true
// footprint centres are closer than 1.8 footprint radii, with the config camera mount.
// Every `failure_every`-th registration failed; `outlier_pairs` registrations get a gross
// error (azimuth + 20 deg, is_outlier = true). Deterministic for a seed.

#include <cmath>
#include <cstdint>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"
#include "nav/core/navigation/sensor_models.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/filter/registration_message.h"
#include "nav/daemon/queue/measurements.h"

namespace nav::testing {

struct SyntheticDiveOptions {
  double speed_mps = 0.5;
  double yaw_rate_radps = 0.0625;  // circle radius 8 m, 100.5 s per turn
  double duration_s = 160.0;
  double image_period_s = 2.0;
  double depth_m = 10.0, altitude_m = 3.0;
  double roll_rad = 0.02, pitch_rad = -0.01, heading0_rad = 0.3;
  int failure_every = 7;
  std::set<std::pair<int, int>> outlier_pairs;  ///< (frame i, frame j) made gross outliers
  std::uint64_t seed = 7;
};

struct SyntheticDive {
  std::vector<daemon::Measurement> measurements;  ///< time-ordered
  daemon::RegistrationTable registrations;
  /// The same registrations, utime = image j's time.
  std::vector<navlcm::registration_t> registration_messages;
  std::vector<std::int64_t> image_t_us;  ///< per frame id
  std::vector<core::Vec12> image_truth;  ///< per frame id
  core::Vec12 final_truth = core::Vec12::Zero();
  int registrations_succeeded = 0;
  std::int64_t truth_origin_us = 0;  ///< monotonic time of truth time 0
};

/// config/sim.yaml for this vehicle. Its roll and pitch are constant, so the filter's roll and
/// pitch rates stay random walks (sim.yaml's attitude_restoring describes the survey simulator's
/// oscillating vehicle): the filter's model then holds exactly.
inline daemon::NavdConfig synthetic_dive_config(const std::string& sim_yaml = "config/sim.yaml") {
  daemon::NavdConfig config = daemon::load_config_file(sim_yaml);
  config.filter.process_noise.attitude_restoring = {};
  return config;
}

inline core::Vec12 synthetic_truth(const SyntheticDiveOptions& o, double t_s) {
  core::Vec12 x = core::Vec12::Zero();
  const double h0 = o.heading0_rad, r = o.yaw_rate_radps, R = o.speed_mps / r;
  // Body velocity (u, 0, 0) rotated by R_world_body: with constant roll/pitch the horizontal
  // velocity is (cos p) u along the heading; the vertical part is removed by w below.
  const Eigen::Vector3d v_body_mps(o.speed_mps, 0.0, 0.0);
  const double h = h0 + r * t_s;
  x(0) = R * std::cos(o.pitch_rad) * (std::sin(h) - std::sin(h0));
  x(1) = -R * std::cos(o.pitch_rad) * (std::cos(h) - std::cos(h0));
  x(2) = o.depth_m;
  x(3) = o.roll_rad;
  x(4) = o.pitch_rad;
  x(5) = core::wrap_angle(h);
  // Body velocity whose world vertical component is zero: w_body chosen so (R v)_z = 0.
  const core::Mat3 R_wb = core::rotation_from_euler(core::Vec3(o.roll_rad, o.pitch_rad, h));
  core::Vec3 v = v_body_mps;
  v(2) = -(R_wb(2, 0) * v(0)) / R_wb(2, 2);
  x.segment<3>(6) = v;
  // Body rates for a constant heading rate r at constant roll/pitch: omega = J2⁻¹ [0 0 r].
  x.segment<3>(9) = core::euler_rate_matrix_inverse(x.segment<3>(3)) * core::Vec3(0, 0, r);
  return x;
}

inline SyntheticDive make_synthetic_dive(const daemon::NavdConfig& config,
                                         const SyntheticDiveOptions& o) {
  SyntheticDive dive;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  core::SensorModels models(daemon::filter_options_from_config(config).sensors);
  int dvl = -1, att = -1, depth = -1, alt = -1, cam = -1;
  for (std::size_t i = 0; i < config.sensors.size(); ++i) {
    const int k = static_cast<int>(i);
    switch (config.sensors[i].type) {
      case daemon::SensorType::kDvlPd0: dvl = k; break;
      case daemon::SensorType::kHeadingNmea: att = k; break;
      case daemon::SensorType::kPressureParo: depth = k; break;
      case daemon::SensorType::kAltimeter: alt = k; break;
      case daemon::SensorType::kCameraGige: cam = k; break;
      default: break;
    }
  }
  const std::int64_t t0_us = 1'000'000'000;
  auto stamp = [&](std::int64_t t_us, int sensor) {
    daemon::MeasurementTime t;
    t.validity_us = t_us;
    t.host_monotonic_us = t_us;
    t.sensor_index = static_cast<std::uint16_t>(sensor);
    return t;
  };
  const auto& cfg_noise = [&](int s) -> const daemon::NoiseSigmas& {
    return config.sensors[static_cast<std::size_t>(s)].noise;
  };
  const std::int64_t tick_us = 200'000;  // 5 Hz
  dive.truth_origin_us = t0_us + tick_us;
  const auto ticks = static_cast<std::int64_t>(o.duration_s * 5.0);
  const auto image_ticks = static_cast<std::int64_t>(std::llround(o.image_period_s * 5.0));
  std::vector<std::int64_t> image_t_us;
  for (std::int64_t k = 1; k <= ticks; ++k) {
    const std::int64_t t_us = t0_us + k * tick_us;
    // Truth time 0 (x = y = 0) is the first tick, where the filter initialises.
    const core::Vec12 x = synthetic_truth(o, 1e-6 * static_cast<double>(t_us - t0_us - tick_us));
    if (k % image_ticks == 0) {
      daemon::ImageEvent image;
      image.time = stamp(t_us, cam);
      image.frame_id = dive.image_truth.size();
      dive.image_truth.push_back(x);
      image_t_us.push_back(t_us);
      dive.measurements.push_back(image);
    }
    daemon::DvlVelocity v;
    v.time = stamp(t_us, dvl);
    const core::MeasVec v_dvl = models.dvl(static_cast<std::size_t>(dvl)).predict(x);
    for (int i = 0; i < 3; ++i) {
      v.v_sensor_mps[static_cast<std::size_t>(i)] = v_dvl(i) + cfg_noise(dvl).velocity_mps * n01(rng);
    }
    dive.measurements.push_back(v);
    daemon::Attitude heading;
    heading.time = stamp(t_us, att);
    heading.has_roll_pitch = false;
    heading.heading_rad = core::wrap_angle(x(5) + cfg_noise(att).heading_rad * n01(rng));
    dive.measurements.push_back(heading);
    daemon::Attitude tilt;
    tilt.time = stamp(t_us, att);
    tilt.has_heading = false;
    tilt.roll_rad = x(3) + cfg_noise(att).roll_pitch_rad * n01(rng);
    tilt.pitch_rad = x(4) + cfg_noise(att).roll_pitch_rad * n01(rng);
    dive.measurements.push_back(tilt);
    if (k % 5 == 1) {
      daemon::Depth d;
      d.time = stamp(t_us, depth);
      d.depth_m = models.depth(static_cast<std::size_t>(depth)).predict(x)(0) +
                  cfg_noise(depth).depth_m * n01(rng);
      dive.measurements.push_back(d);
      daemon::Altitude a;
      a.time = stamp(t_us, alt);
      a.altitude_m = o.altitude_m;
      dive.measurements.push_back(a);
    }
    dive.final_truth = x;
  }
  // Oracle registrations.
  const core::CameraRelativePoseModel& camera = *models.camera();
  const double r_fp = o.altitude_m * models.footprint_radius_per_altitude();
  const double sd_dir = 0.5 * M_PI / 180.0, sd_rot = 0.2 * M_PI / 180.0;
  int pairs = 0;
  for (std::size_t j = 1; j < dive.image_truth.size(); ++j) {
    for (std::size_t i = 0; i < j; ++i) {
      const core::Vec6 c_i = core::head_to_tail(dive.image_truth[i].head<6>(), camera.x_body_camera);
      const core::Vec6 c_j = core::head_to_tail(dive.image_truth[j].head<6>(), camera.x_body_camera);
      if ((c_i.head<2>() - c_j.head<2>()).norm() >= 1.8 * r_fp) continue;
      navlcm::registration_t reg{};
      reg.utime = image_t_us[j];
      reg.frame_id_i = static_cast<std::int64_t>(i);
      reg.frame_id_j = static_cast<std::int64_t>(j);
      reg.success = (++pairs % o.failure_every) != 0;
      const core::MeasVec z = camera.predict(dive.image_truth[i], dive.image_truth[j]);
      const double sd[5] = {sd_dir, sd_dir, sd_rot, sd_rot, sd_rot};
      for (int k = 0; k < 5; ++k) {
        reg.measurement[k] = core::wrap_angle(z(k) + sd[k] * n01(rng));
        for (int l = 0; l < 5; ++l) reg.covariance[k * 5 + l] = k == l ? sd[k] * sd[k] : 0.0;
      }
      reg.is_outlier = o.outlier_pairs.count({static_cast<int>(i), static_cast<int>(j)}) > 0;
      if (reg.is_outlier) {
        reg.success = true;
        reg.measurement[0] = core::wrap_angle(reg.measurement[0] + 20.0 * M_PI / 180.0);
      }
      reg.overlap_fraction = 1.0 - (c_i.head<2>() - c_j.head<2>()).norm() / (2.0 * r_fp);
      if (reg.success) ++dive.registrations_succeeded;
      dive.registrations.insert(daemon::registration_from_message(reg));
      dive.registration_messages.push_back(reg);
    }
  }
  dive.image_t_us = image_t_us;
  return dive;
}

}  // namespace nav::testing
