// A simulated dive played by the dive-log source (daemon/include/nav/daemon/sources/
// dive_log_source.h) through navd's sensor decoders: every RAW_* message decodes, no device is
// unknown, every image arrives, validity times land on the simulator's sample times, and the
// decoded values agree with truth.csv (DVL in its own frame at its lever arm, heading, depth).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <thread>

#include "nav/daemon/sources/dive_log_source.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

Eigen::Matrix3d rotation_zyx(const std::array<double, 3>& rpy) {
  return (Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

double wrap(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

TEST(SimDiveSource, EveryMessageDecodesOntoTheSimulatorsClockAndTruth) {
  const auto dir = scratch_dir("dive_source");
  SimOptions options = sim_options(dir, 5, 12);
  const SimSummary summary = simulate_dive(options, sim_config_path().string());
  const daemon::NavdConfig config = daemon::load_config_file((dir / "config.yaml").string());
  const TruthTable truth = read_truth(dir);

  daemon::MeasurementQueue queue(1024);
  std::atomic<bool> stop{false}, done{false};
  daemon::DiveLogSourceOptions play;
  play.as_fast_as_possible = true;
  daemon::DiveLogSourceCounters c;
  std::thread source([&] {
    c = daemon::run_dive_log_source((dir / "dive.lcmlog").string(), config, play, queue, stop,
                                    done);
  });
  std::vector<daemon::Measurement> got;
  for (bool finished = false; !finished;) {
    finished = done.load();
    queue.pop_bulk(got, 4096);
    if (!finished) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  source.join();
  queue.pop_bulk(got, 1 << 20);

  // No checksum, framing or range error anywhere (the PD0 leader carries the DVL's compass
  // and tilts, so no leader field is written out of range).
  for (std::size_t i = 0; i < c.sensors.size(); ++i) {
    EXPECT_EQ(c.sensors[i].decode_errors, 0u) << config.sensors[i].name;
  }
  EXPECT_EQ(c.decode_errors, 0u);
  EXPECT_EQ(c.unknown_devices, 0u);
  EXPECT_EQ(c.queue_drops, 0u);
  EXPECT_EQ(static_cast<std::int64_t>(c.images), summary.images);
  EXPECT_EQ(c.measurements, got.size());
  EXPECT_EQ(static_cast<std::int64_t>(c.sensors[0].messages), summary.sensors.dvl_ensembles);
  EXPECT_EQ(static_cast<std::int64_t>(c.sensors[0].invalid), summary.sensors.dvl_invalid_ensembles);
  EXPECT_GT(c.sensors[0].device_clock, c.sensors[0].measurements * 9 / 10);

  const daemon::SensorConfig& dvl = config.sensors[0];
  const Eigen::Matrix3d R_body_dvl = rotation_zyx(dvl.mount.rpy_rad);
  const Eigen::Vector3d lever(dvl.mount.lever_arm_m.data());
  double max_offset_us = 0.0, dvl_sq = 0.0, heading_sq = 0.0, depth_sum = 0.0;
  long n_dvl = 0, n_heading = 0, n_depth = 0;
  for (const daemon::Measurement& m : got) {
    const std::int64_t v = daemon::validity_us(m);
    if (std::holds_alternative<daemon::ImageEvent>(m)) continue;
    // Sample times are on the simulator's 50 ms grid; decoded validity = true + jitter (+ the
    // gap after a previous sentence in the same read), or the DVL's mapped RTC.
    const std::int64_t since = v - truth.t0_us;
    const std::int64_t tick = truth.t0_us + (since + 25'000) / 50'000 * 50'000;
    max_offset_us = std::max(max_offset_us, std::abs(double(v - tick)));
    const core::Vec12& x = truth.at(tick);
    if (const auto* d = std::get_if<daemon::DvlVelocity>(&m)) {
      const Eigen::Vector3d v_body(x[6], x[7], x[8]), w_body(x[9], x[10], x[11]);
      const Eigen::Vector3d want = R_body_dvl.transpose() * (v_body + w_body.cross(lever));
      dvl_sq += (Eigen::Vector3d(d->v_sensor_mps.data()) - want).squaredNorm() / 3.0;
      ++n_dvl;
    } else if (const auto* a = std::get_if<daemon::Attitude>(&m); a && a->has_heading) {
      heading_sq += std::pow(wrap(a->heading_rad - x[5]), 2);
      ++n_heading;
    } else if (const auto* z = std::get_if<daemon::Depth>(&m)) {
      depth_sum += z->depth_m - x[2];
      ++n_depth;
    }
  }
  const double dvl_rms = std::sqrt(dvl_sq / n_dvl), heading_rms = std::sqrt(heading_sq / n_heading);
  std::printf(
      "%zu measurements: max |validity - sample time| %.1f ms, DVL residual RMS %.4f m/s, "
      "heading RMS %.3f deg, mean depth residual %.3f m\n",
      got.size(), max_offset_us * 1e-3, dvl_rms, heading_rms * 180.0 / std::numbers::pi,
      depth_sum / n_depth);
  EXPECT_LT(max_offset_us, 12'000.0);
  EXPECT_LT(dvl_rms, 0.02);  // 0.01 m/s noise, 0.1 % scale error (a sign error would be ~0.5)
  EXPECT_LT(heading_rms, 0.3 * std::numbers::pi / 180.0);  // 0.1 deg noise + 0.05 deg bias
  EXPECT_LT(std::abs(depth_sum / n_depth), 0.3);           // lever arm (0.2 m up) and 0.02 m bias
}

}  // namespace
}  // namespace nav::sim::test
