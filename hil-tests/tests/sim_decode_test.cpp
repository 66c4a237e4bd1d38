// The dive log's raw bytes decode back through the drivers' decoders (PD0 streaming decoder,
// NMEA, Paroscientific, PA500 altimeter) to the truth within the configured noise: residual
// RMS ~ the config sigma, mean ~ 0 without biases and ~ the bias with them; the DVL measures
// its own location's velocity in its own frame (config mount); bottom-lock dropouts appear as
// invalid bottom track; host times = validity + latency + jitter.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <variant>
#include <vector>

#include "nav/core/geometry/rotation.h"
#include "nav/drivers/codecs/altimeter.h"
#include "nav/drivers/codecs/nmea.h"
#include "nav/drivers/codecs/paroscientific.h"
#include "nav/drivers/codecs/pd0.h"
#include "nav/drivers/codecs/seawater.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);
constexpr double kDeg = std::numbers::pi / 180.0;

/// Residual statistics of one measured quantity.
struct Stat {
  double sum = 0.0, sum_sq = 0.0;
  long n = 0;
  void add(double r) {
    sum += r;
    sum_sq += r * r;
    ++n;
  }
  double mean() const { return sum / n; }
  double rms() const { return std::sqrt(sum_sq / n); }
  double sd() const { return std::sqrt(sum_sq / n - mean() * mean()); }
};

struct Residuals {
  Stat dvl[3], heading, roll, pitch, depth, altitude, host_minus_validity_us;
  long dvl_valid = 0, dvl_invalid = 0;
  std::int64_t max_latency_us = 0;
  std::vector<double> altitude_abs;  ///< |range - vertical distance to the seafloor below|
  double altitude_median_abs() const {
    std::vector<double> v = altitude_abs;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  }
};

constexpr std::uint64_t kSeed = 11;
constexpr int kImages = 120;

/// The dive's seafloor, rebuilt as simulate_dive builds it (mission extent, seed stream 1).
Seafloor dive_seafloor() {
  MissionOptions m;
  m.images = kImages;
  const Mission mission = plan_mission(m);
  return Seafloor(mission.extent, mission.wreck_x_m, mission.wreck_y_m, {}, derive_seed(kSeed, 1));
}

/// The tick (on the 50 ms sensor grid) at or before host time - config latency: the time of
/// validity of a sample (the simulator's jitter and inter-sentence gap are < 50 ms).
std::int64_t validity_of(std::int64_t host_us, double latency_s, const TruthTable& truth) {
  const std::int64_t since = host_us - std::llround(latency_s * 1e6) - truth.t0_us;
  return truth.t0_us + since / 50000 * 50000;
}

Residuals decode_dive(const std::filesystem::path& dir, const SimSummary& s,
                      const SensorErrorOptions& errors) {
  const Seafloor floor = dive_seafloor();
  const daemon::NavdConfig cfg = daemon::load_config_file((dir / "config.yaml").string());
  const TruthTable truth = read_truth(dir);
  const daemon::SensorConfig& dvl_cfg = cfg.sensors[0];
  const daemon::SensorConfig& depth_cfg = cfg.sensors[2];
  const core::Mat3 R_body_dvl = core::rotation_from_euler(
      core::Vec3(dvl_cfg.mount.rpy_rad[0], dvl_cfg.mount.rpy_rad[1], dvl_cfg.mount.rpy_rad[2]));
  const core::Vec3 lever(dvl_cfg.mount.lever_arm_m[0], dvl_cfg.mount.lever_arm_m[1],
                         dvl_cfg.mount.lever_arm_m[2]);
  const core::Vec3 depth_lever(depth_cfg.mount.lever_arm_m[0], depth_cfg.mount.lever_arm_m[1],
                               depth_cfg.mount.lever_arm_m[2]);
  drivers::Pd0Decoder pd0;
  drivers::NmeaDecoder nmea;
  drivers::ParoDecoder paro;
  drivers::AltimeterDecoder alt;
  drivers::DepthConversionOptions depth_opt;
  depth_opt.latitude_rad = depth_cfg.pressure.latitude_deg * kDeg;
  depth_opt.atmospheric_pressure_pa = depth_cfg.pressure.surface_pressure_dbar * 1e4;

  Residuals r;
  std::vector<drivers::Pd0Ensemble> ens;
  std::vector<drivers::NmeaRecord> sentences;
  std::vector<drivers::ParoRecord> replies;
  std::vector<drivers::AltimeterRecord> ranges;
  for (const daemon::DiveLogEvent& ev : read_log(dir)) {
    const auto* raw = std::get_if<navlcm::raw_bytes_t>(&ev);
    if (!raw) continue;
    EXPECT_EQ(raw->utime, realtime_of(raw->host_monotonic_us));
    const drivers::HostTime host{raw->host_monotonic_us, raw->utime};
    const std::span<const std::uint8_t> bytes(raw->data.data(), raw->data.size());
    const daemon::SensorConfig* sensor = nullptr;
    for (const daemon::SensorConfig& c : cfg.sensors)
      if (c.name == raw->device) sensor = &c;
    EXPECT_NE(sensor, nullptr) << raw->device;
    if (!sensor) continue;
    const std::int64_t t = validity_of(raw->host_monotonic_us, sensor->latency_s, truth);
    const core::Vec12& x = truth.at(t);
    // Host time beyond validity + the config latency: jitter and the gap after a sentence.
    r.max_latency_us = std::max<std::int64_t>(
        r.max_latency_us, raw->host_monotonic_us - t - std::llround(sensor->latency_s * 1e6));
    if (raw->device == "dvl") {
      ens.clear();
      pd0.feed(bytes, host, ens);
      for (const drivers::Pd0Ensemble& e : ens) {
        // The RTC (10 ms resolution) minus the DVL clock offset and drift gives the validity.
        const double since_s = (*e.time.sensor_time_us - kDiveStartRealtimeUs) * 1e-6;
        const std::int64_t rtc_mono =
            *e.time.sensor_time_us - kDiveStartRealtimeUs + kDiveStartMonotonicUs -
            std::llround((errors.dvl_clock_offset_s + errors.dvl_clock_drift_ppm * 1e-6 * since_s) *
                         1e6);
        const std::int64_t validity =
            (rtc_mono - truth.t0_us + 25000) / 50000 * 50000 + truth.t0_us;
        EXPECT_LE(std::abs(rtc_mono - validity), 10100)
            << "RTC far from its tick (10 ms resolution)";
        const core::Vec12& xv = truth.at(validity);
        const core::Vec3 v_dvl =
            R_body_dvl.transpose() * (xv.segment<3>(6) + xv.segment<3>(9).cross(lever));
        if (!e.bottom_track || !e.bottom_track->velocity_valid()) {
          ++r.dvl_invalid;
          continue;
        }
        ++r.dvl_valid;
        for (int i = 0; i < 3; ++i)
          r.dvl[i].add(-*e.bottom_track->velocity_mps[static_cast<std::size_t>(i)] -
                       (1.0 + errors.dvl_scale_error) * v_dvl[i]);
      }
    } else if (raw->device == "heading") {
      sentences.clear();
      nmea.feed(bytes, host, sentences);
      for (const drivers::NmeaRecord& rec : sentences) {
        if (const auto* h = std::get_if<drivers::NmeaHeading>(&rec)) {
          r.heading.add(core::wrap_angle(h->heading_rad - x[5]));
        } else if (const auto* a = std::get_if<drivers::NmeaAttitude>(&rec)) {
          r.roll.add(a->roll_rad - x[3]);
          r.pitch.add(a->pitch_rad - x[4]);
        }
      }
    } else if (raw->device == "depth") {
      replies.clear();
      paro.feed(bytes, host, replies);
      for (const drivers::ParoRecord& p : replies) {
        const double z = x[2] + (core::rotation_from_euler(x.segment<3>(3)) * depth_lever).z();
        r.depth.add(*drivers::depth_from_pressure_m(p.pressure_pa, depth_opt) - z);
      }
    } else if (raw->device == "altimeter") {
      ranges.clear();
      alt.feed(bytes, host, ranges);
      for (const drivers::AltimeterRecord& a : ranges) {
        EXPECT_TRUE(a.range_m.has_value());
        // The range along the body z axis (the altimeter has no mount in sim.yaml), found
        // here by marching down the axis in 1 cm steps until it is below the seafloor.
        const core::Vec3 axis = core::rotation_from_euler(x.segment<3>(3)) * core::Vec3::UnitZ();
        double along = 0.0;
        while (along < 100.0) {
          const core::Vec3 q = x.head<3>() + along * axis;
          if (q.z() >= floor.depth_m(q.x(), q.y())) break;
          along += 0.01;
        }
        r.altitude_abs.push_back(std::abs(*a.range_m - along));
      }
    }
  }
  EXPECT_EQ(pd0.stats().checksum_failures + pd0.stats().malformed + pd0.stats().dropped_bytes +
                pd0.stats().out_of_range,
            0u);
  EXPECT_EQ(nmea.stats().checksum_failures + nmea.stats().malformed, 0u);
  EXPECT_EQ(paro.stats().records, static_cast<std::uint64_t>(s.sensors.depth_replies));
  EXPECT_EQ(alt.stats().records, static_cast<std::uint64_t>(s.sensors.altimeter_lines));
  return r;
}

SimSummary simulate(const std::filesystem::path& dir, const SensorErrorOptions& errors) {
  SimOptions o = sim_options(dir, kSeed, kImages);
  o.sensor_errors = errors;
  return simulate_dive(o, sim_config_path().string());
}

TEST(SimDecode, IdealSensorsDecodeToTruthWithinTheirNoise) {
  const auto dir = scratch_dir("ideal");
  const SensorErrorOptions errors = SensorErrorOptions::ideal();
  const SimSummary s = simulate(dir, errors);
  const Residuals r = decode_dive(dir, s, errors);
  EXPECT_EQ(r.dvl_valid, s.sensors.dvl_ensembles);
  EXPECT_EQ(r.dvl_invalid, 0);
  for (int i = 0; i < 3; ++i) {  // config: 0.01 m/s; PD0 quantises to 1 mm/s
    EXPECT_NEAR(r.dvl[i].rms(), 0.01, 0.001) << "axis " << i;
    EXPECT_NEAR(r.dvl[i].mean(), 0.0, 0.0005) << "axis " << i;
  }
  EXPECT_NEAR(r.heading.rms(), 0.1 * kDeg, 0.01 * kDeg);  // HDT: 0.001 deg resolution
  EXPECT_NEAR(r.roll.rms(), 0.1 * kDeg, 0.01 * kDeg);     // PHTRO: 0.01 deg resolution
  EXPECT_NEAR(r.pitch.rms(), 0.1 * kDeg, 0.01 * kDeg);
  EXPECT_NEAR(r.heading.mean(), 0.0, 0.01 * kDeg);
  EXPECT_NEAR(r.depth.rms(), 0.01, 0.001);
  EXPECT_NEAR(r.depth.mean(), 0.0, 0.001);
  EXPECT_GT(r.heading.n, 9000);
  // Median |N(0, 0.1 m)| = 0.0674 m; PA500 lines carry 1 cm, the march 1 cm steps.
  EXPECT_NEAR(r.altitude_median_abs(), 0.0674, 0.01);
  // host time = validity + config latency + jitter (<= 2 ms) + the gap after HDT (< 3 ms).
  EXPECT_LE(r.max_latency_us, 5000);
}

TEST(SimDecode, BiasesAndDropoutsShowUpAsConfigured) {
  const auto dir = scratch_dir("biased");
  SensorErrorOptions errors;  // defaults: small biases, clock offset and drift, dropouts
  errors.heading_bias_rad = 0.5 * kDeg;
  errors.depth_bias_m = 0.1;
  errors.dvl_scale_error = 0.01;
  errors.dvl_dropouts_per_hour = 10.0;
  const SimSummary s = simulate(dir, errors);
  const Residuals r = decode_dive(dir, s, errors);  // DVL residual relative to the scaled truth
  EXPECT_EQ(r.dvl_invalid, s.sensors.dvl_invalid_ensembles);
  EXPECT_GT(r.dvl_invalid, 25);  // at least one dropout of >= 10 s at 5 Hz
  EXPECT_EQ(r.dvl_valid + r.dvl_invalid, s.sensors.dvl_ensembles);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(r.dvl[i].rms(), 0.01, 0.0012) << "axis " << i;
  EXPECT_NEAR(r.heading.mean(), 0.5 * kDeg, 0.01 * kDeg);
  EXPECT_NEAR(r.roll.mean(), errors.roll_pitch_bias_rad, 0.01 * kDeg);
  EXPECT_NEAR(r.depth.mean(), 0.1, 0.002);
  EXPECT_NEAR(r.depth.sd(), 0.01, 0.001);
}

TEST(SimDecode, UnescoPressureInverseIsExact) {
  for (double depth : {0.0, 10.0, 1000.0, 3800.0, 6000.0}) {
    const double p = unesco1983_sea_pressure_dbar(depth, 41.73 * kDeg);
    EXPECT_NEAR(drivers::unesco1983_depth_m(p, 41.73 * kDeg), depth, 1e-8);
  }
}

}  // namespace
}  // namespace nav::sim::test
