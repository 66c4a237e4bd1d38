// A simulated dive replays through navd's own dive-log source and sensor decoders
// (daemon/sources) without a decode error: every sensor's measurements come back at the
// simulator's times of validity (the DVL's through its RTC clock mapping) and values.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <atomic>
#include <cmath>
#include <numbers>

#include "nav/core/geometry/rotation.h"
#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/sources/dive_log_source.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

struct Stat {
  double sum = 0.0, sum_sq = 0.0;
  long n = 0;
  void add(double r) {
    sum += r;
    sum_sq += r * r;
    ++n;
  }
  double mean() const { return sum / n; }
  double sd() const { return std::sqrt(sum_sq / n - mean() * mean()); }
};

TEST(SimReplaySource, DiveDecodesThroughNavdsSourceAtTheTruth) {
  const auto dir = scratch_dir("replay");
  SimOptions o;
  o.out_dir = dir.string();
  o.seed = 21;
  o.sensor_errors = SensorErrorOptions::with_sensor_biases();  // biases must decode as such
  o.mission.images = 60;  // default sensor errors: biases, DVL clock offset/drift, dropouts
  const SimSummary s = simulate_dive(o, sim_config_path().string());
  const daemon::NavdConfig cfg = daemon::load_config_file((dir / "config.yaml").string());
  const TruthTable truth = read_truth(dir);
  const auto images = read_csv(dir / "images.csv");

  const std::string log = (dir / "dive.lcmlog").string();
  EXPECT_EQ(static_cast<std::int64_t>(daemon::load_registrations(log).size()), s.registrations);
  daemon::MeasurementQueue queue(1 << 16);
  std::atomic<bool> stop{false}, done{false};
  daemon::DiveLogSourceOptions options;
  options.as_fast_as_possible = true;
  const daemon::DiveLogSourceCounters c =
      daemon::run_dive_log_source(log, cfg, options, queue, stop, done);
  EXPECT_EQ(c.decode_errors, 0u);
  for (std::size_t i = 0; i < c.sensors.size(); ++i)
    EXPECT_EQ(c.sensors[i].decode_errors, 0u) << cfg.sensors[i].name;
  EXPECT_EQ(c.unknown_devices, 0u);
  EXPECT_EQ(c.queue_drops, 0u);
  EXPECT_EQ(c.images, 60u);
  EXPECT_EQ(c.registrations, static_cast<std::uint64_t>(s.registrations));
  ASSERT_EQ(c.sensors.size(), cfg.sensors.size());
  EXPECT_EQ(c.sensors[0].invalid, static_cast<std::uint64_t>(s.sensors.dvl_invalid_ensembles));
  EXPECT_GT(c.sensors[0].device_clock, c.sensors[0].measurements * 9 / 10)
      << "DVL dated by its RTC";

  const SensorErrorOptions& e = o.sensor_errors;
  const core::Mat3 R_body_dvl = core::rotation_from_euler(
      core::Vec3(cfg.sensors[0].mount.rpy_rad[0], cfg.sensors[0].mount.rpy_rad[1],
                 cfg.sensors[0].mount.rpy_rad[2]));
  const core::Vec3 lever(cfg.sensors[0].mount.lever_arm_m[0], cfg.sensors[0].mount.lever_arm_m[1],
                         cfg.sensors[0].mount.lever_arm_m[2]);
  Stat dvl, heading, depth;
  std::int64_t worst_dvl_time_us = 0, worst_ascii_time_us = 0;
  std::size_t image_k = 0;
  std::vector<daemon::Measurement> got;
  queue.pop_bulk(got, 1 << 16);
  for (const daemon::Measurement& m : got) {
    const std::int64_t v = daemon::validity_us(m);
    const std::int64_t tick = truth.t0_us + (v - truth.t0_us + 25000) / 50000 * 50000;
    const core::Vec12& x = truth.at(tick);
    if (const auto* d = std::get_if<daemon::DvlVelocity>(&m)) {
      worst_dvl_time_us = std::max<std::int64_t>(worst_dvl_time_us, std::abs(v - tick));
      const core::Vec3 v_dvl =
          R_body_dvl.transpose() * (x.segment<3>(6) + x.segment<3>(9).cross(lever));
      for (int i = 0; i < 3; ++i)
        dvl.add(d->v_sensor_mps[static_cast<std::size_t>(i)] -
                (1.0 + e.dvl_scale_error) * v_dvl[i]);
    } else if (const auto* a = std::get_if<daemon::Attitude>(&m)) {
      worst_ascii_time_us = std::max<std::int64_t>(worst_ascii_time_us, std::abs(v - tick));
      if (a->has_heading) heading.add(core::wrap_angle(a->heading_rad - x[5]));
    } else if (const auto* z = std::get_if<daemon::Depth>(&m)) {
      worst_ascii_time_us = std::max<std::int64_t>(worst_ascii_time_us, std::abs(v - tick));
      const core::Vec3 arm(cfg.sensors[2].mount.lever_arm_m[0], cfg.sensors[2].mount.lever_arm_m[1],
                           cfg.sensors[2].mount.lever_arm_m[2]);
      depth.add(z->depth_m - (x[2] + (core::rotation_from_euler(x.segment<3>(3)) * arm).z()));
    } else if (const auto* im = std::get_if<daemon::ImageEvent>(&m)) {
      ASSERT_LT(image_k, images.size());
      EXPECT_EQ(im->frame_id, static_cast<std::uint64_t>(images[image_k][0]));
      EXPECT_EQ(v, static_cast<std::int64_t>(images[image_k][1]));
      ++image_k;
    }
  }
  EXPECT_EQ(image_k, 60u);
  std::printf(
      "DVL residual mean %.5f sd %.5f m/s (n %ld), worst DVL time error %lld us, "
      "worst ASCII time error %lld us, heading mean %.4f deg, depth mean %.4f sd %.4f m\n",
      dvl.mean(), dvl.sd(), dvl.n, static_cast<long long>(worst_dvl_time_us),
      static_cast<long long>(worst_ascii_time_us), heading.mean() * 180 / std::numbers::pi,
      depth.mean(), depth.sd());
  EXPECT_LE(worst_ascii_time_us, 5000) << "jitter <= 2 ms plus the gap after HDT";
  EXPECT_LE(worst_dvl_time_us, 20000) << "RTC: 10 ms resolution, offset and drift mapped away";
  EXPECT_NEAR(dvl.sd(), 0.01, 0.0015);
  EXPECT_NEAR(dvl.mean(), 0.0, 0.001);
  EXPECT_NEAR(heading.mean(), e.heading_bias_rad, 0.02 * std::numbers::pi / 180.0);
  EXPECT_NEAR(depth.mean(), e.depth_bias_m, 0.003);
  EXPECT_NEAR(depth.sd(), 0.01, 0.0015);
}

}  // namespace
}  // namespace nav::sim::test
