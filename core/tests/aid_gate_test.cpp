// The innovation gate of NavFilter's robot updates (nav/core/navigation/aid_gate.h) on a
// vehicle moving straight north at 0.5 m/s with noise-free DVL, attitude and depth messages:
// for each kind (DVL velocity, roll/pitch, heading, depth) a 10-sigma outlier is rejected,
// counted, and leaves the information matrix, vector, mean and published covariance
// bit-identical, while a 1-sigma one is fused; a heading stuck for less than the reset timeout
// is refused throughout although the dead-reckoned heading's covariance grows; a real heading
// step is fused again after the timeout and the estimate follows it; the chi-square gates
// match closed forms.
#include "nav/core/navigation/aid_gate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "nav/core/navigation/nav_filter.h"
#include "nav/testing/filter_sensors.h"

namespace nav::core {
namespace {

constexpr double kSpeedMps = 0.5;
constexpr double kDepthM = 20.0;
constexpr std::size_t kDvl = 0, kAttitude = 1, kDepth = 2;

NavFilterOptions options(double reset_timeout_s = 60.0) {
  NavFilterOptions o;
  o.sensors = nav::testing::named_sensors({"dvl", "attitude", "depth"});
  o.propose_links = false;
  // config/sim.yaml's yaw PSD: without heading updates the heading sigma reaches 0.3 rad in 8 s.
  o.process_noise.angular_accel_psd = Vec3(7e-5, 2.5e-5, 6e-4);
  o.aid_gate.reset_timeout_s = reset_timeout_s;
  return o;
}

MeasurementTime at(std::int64_t t_us, std::size_t sensor) {
  return MeasurementTime{t_us, t_us, t_us, static_cast<std::uint16_t>(sensor)};
}

/// Messages in [from_s, to_s): attitude 10 Hz (its heading from heading_rad(t)), DVL 5 Hz, depth
/// 2 Hz, on the straight run north.
template <class Heading>
std::vector<Measurement> run(double from_s, double to_s, Heading heading_rad) {
  std::vector<Measurement> out;
  for (auto t = static_cast<std::int64_t>(from_s * 1e6); t < static_cast<std::int64_t>(to_s * 1e6);
       t += 100'000) {
    out.push_back(Attitude{at(t, kAttitude), 0.0, 0.0, heading_rad(t), true, true});
    if (t % 200'000 == 0) out.push_back(DvlVelocity{at(t + 1'000, kDvl), {kSpeedMps, 0.0, 0.0}});
    if (t % 500'000 == 0) out.push_back(Depth{at(t + 2'000, kDepth), kDepthM});
  }
  return out;
}
std::vector<Measurement> straight(double from_s, double to_s) {
  return run(from_s, to_s, [](std::int64_t) { return 0.0; });
}

void feed(NavFilter& f, const std::vector<Measurement>& ms) {
  for (const Measurement& m : ms) ASSERT_TRUE(f.process(m).ok());
}

const SensorInnovation& record_of(const NavFilter& f, const std::string& name) {
  for (const SensorInnovation& s : f.innovations().sensors()) {
    if (s.name == name) return s;
  }
  throw std::runtime_error("no innovation record for " + name);
}

struct Case {
  const char* name;
  std::string sensor;
  int component;  ///< in the sensor's `last` (attitude: roll, pitch, then heading)
};

/// One message of `c` at t_us whose component is offset by `offset` from the truth.
Measurement offset_message(const Case& c, std::int64_t t_us, double offset) {
  if (c.sensor == "dvl") {
    DvlVelocity m{at(t_us, kDvl), {kSpeedMps, 0.0, 0.0}};
    m.v_sensor_mps[static_cast<std::size_t>(c.component)] += offset;
    return m;
  }
  if (c.sensor == "depth") return Depth{at(t_us, kDepth), kDepthM + offset};
  if (c.component == 2) return Attitude{at(t_us, kAttitude), 0.0, 0.0, offset, false, true};
  Attitude m{at(t_us, kAttitude), 0.0, 0.0, 0.0, true, false};
  (c.component == 0 ? m.roll_rad : m.pitch_rad) = offset;
  return m;
}

TEST(AidGate, RejectsATenSigmaOutlierBitIdenticallyAndFusesAOneSigmaOneForEachKind) {
  NavFilter settled(options(), nullptr);
  feed(settled, straight(0.0, 20.0));
  for (const Case& c :
       {Case{"DVL surge", "dvl", 0}, Case{"DVL heave", "dvl", 2}, Case{"roll", "attitude", 0},
        Case{"pitch", "attitude", 1}, Case{"heading", "attitude", 2}, Case{"depth", "depth", 0}}) {
    const std::int64_t t_us = 20'050'000;
    // sqrt(S) of this component from the last update (the 50 ms prediction adds < 1 %).
    const InnovationComponent& last =
        record_of(settled, c.sensor).last[static_cast<std::size_t>(c.component)];
    ASSERT_GT(last.innovation_variance, 0.0) << c.name;
    const double sigma = std::sqrt(last.innovation_variance);

    NavFilter outlier(settled);
    const std::uint64_t rejected = record_of(outlier, c.sensor).rejected;
    // Predict to t first (a message of another sensor), so the outlier only meets the gate.
    ASSERT_TRUE(outlier.process(Altitude{at(t_us - 1'000, kDepth), 3.0}).ok());
    const Eigen::VectorXd mean = outlier.esdf().mean();
    const Eigen::VectorXd eta = outlier.esdf().information_vector();
    const Eigen::MatrixXd lambda = Eigen::MatrixXd(outlier.esdf().information().to_sparse());
    const Mat12 published = outlier.robot_covariance();
    ASSERT_TRUE(outlier.process(offset_message(c, t_us, 10.0 * sigma)).ok());
    EXPECT_EQ(record_of(outlier, c.sensor).rejected, rejected + 1) << c.name;
    EXPECT_FALSE(record_of(outlier, c.sensor).last[static_cast<std::size_t>(c.component)].fused);
    EXPECT_TRUE(outlier.esdf().mean() == mean) << c.name;
    EXPECT_TRUE(outlier.esdf().information_vector() == eta) << c.name;
    EXPECT_TRUE(Eigen::MatrixXd(outlier.esdf().information().to_sparse()) == lambda) << c.name;
    EXPECT_TRUE(outlier.robot_covariance() == published) << c.name;

    NavFilter inlier(settled);
    const std::uint64_t updates = record_of(inlier, c.sensor).updates;
    ASSERT_TRUE(inlier.process(offset_message(c, t_us, 1.0 * sigma)).ok());
    EXPECT_EQ(record_of(inlier, c.sensor).updates, updates + 1) << c.name;
    EXPECT_EQ(record_of(inlier, c.sensor).rejected, rejected) << c.name;
    EXPECT_FALSE(inlier.esdf().mean() == settled.esdf().mean()) << c.name;
  }
}

TEST(AidGate, AStuckHeadingShorterThanTheTimeoutIsRefusedThroughout) {
  // Heading stuck 1 rad off for 8 s (80 messages) with a 10-s reset: dead reckoning grows the
  // heading's covariance, the run's gate keeps the one it opened with.
  NavFilter f(options(10.0), nullptr);
  feed(f, straight(0.0, 20.0));
  const std::uint64_t rejected = record_of(f, "attitude").rejected;
  feed(f, run(20.0, 28.0, [](std::int64_t) { return 1.0; }));
  EXPECT_EQ(record_of(f, "attitude").rejected, rejected + 80);
  EXPECT_EQ(record_of(f, "attitude").gate_resets, 0u);
  EXPECT_NEAR(f.esdf().mean_block(Esdf::kRobotBlock)(5), 0.0, 1e-3) << "heading kept";
  // The heading's variance grew so far that a gate on the current S would let the stuck value
  // through (1 rad within 5 sigma): the run's gate is what refuses it.
  const double heading_var = f.robot_covariance()(5, 5);
  EXPECT_LT(1.0, 5.0 * std::sqrt(heading_var)) << "heading sigma " << std::sqrt(heading_var);
  feed(f, straight(28.0, 30.0));  // the sensor recovers: fused at once, the run closes
  EXPECT_EQ(record_of(f, "attitude").rejected, rejected + 80);
  EXPECT_TRUE(record_of(f, "attitude").last[2].fused);
}

TEST(AidGate, ARealHeadingStepIsFusedAgainAfterTheTimeout) {
  // The heading sensor steps by 0.3 rad for good (a real jump, e.g. a recalibration): refused
  // for the 10-s timeout, then fused until the estimate meets it, and gated normally after.
  NavFilter f(options(10.0), nullptr);
  feed(f, straight(0.0, 20.0));
  const std::uint64_t rejected = record_of(f, "attitude").rejected;
  feed(f, run(20.0, 45.0, [](std::int64_t) { return 0.3; }));
  const SensorInnovation& s = record_of(f, "attitude");
  EXPECT_GE(s.rejected - rejected, 99u);  // 10 s of heading at 10 Hz, the roll/pitch fused
  EXPECT_LE(s.rejected - rejected, 101u);
  EXPECT_GT(s.gate_resets, 0u);
  EXPECT_NEAR(f.esdf().mean_block(Esdf::kRobotBlock)(5), 0.3, 0.01) << "estimate followed";
  EXPECT_TRUE(s.last[2].fused);
  EXPECT_LT(s.last[2].test_ratio, 1.0);
}

TEST(AidGate, AHeadingBackAfterAFaultIsNotLockedOutAgainAfterTheReset) {
  // The vehicle starts turning at 0.1 rad/s at 20 s while the heading sensor is stuck at 1 rad
  // (20-28 s); the dead-reckoned heading keeps its old rate. The honest heading from 28 s is
  // refused until the 10-s reset (30 s), fused again, and the estimate must then follow it
  // without a new run locking it out (the turn rate is learnt while the reset lasts).
  const auto truth = [](std::int64_t t_us) {
    const double t_s = 1e-6 * static_cast<double>(t_us);
    return std::remainder(t_s < 20.0 ? 0.0 : 0.1 * (t_s - 20.0), 2.0 * M_PI);
  };
  NavFilter f(options(10.0), nullptr);
  feed(f, straight(0.0, 20.0));
  feed(f, run(20.0, 28.0, [](std::int64_t) { return 1.0; }));
  feed(f, run(28.0, 40.0, truth));
  const std::uint64_t rejected = record_of(f, "attitude").rejected;
  EXPECT_GT(record_of(f, "attitude").gate_resets, 0u);
  feed(f, run(40.0, 60.0, truth));
  EXPECT_EQ(record_of(f, "attitude").rejected, rejected) << "refused again after the reset";
  const double error =
      std::remainder(f.esdf().mean_block(Esdf::kRobotBlock)(5) - truth(f.time_us()), 2.0 * M_PI);
  EXPECT_NEAR(error, 0.0, 0.01);
}

TEST(AidGate, ChiSquareGatesMatchClosedForms) {
  const AidGate gate(AidGateOptions{});
  // 1 dof: g²; 2 dof: -2 ln(1 - p) with 1 - p = erfc(g / sqrt 2).
  EXPECT_NEAR(gate.chi2_gate(AidKind::kHeading, 1), 25.0, 1e-8);
  EXPECT_NEAR(gate.chi2_gate(AidKind::kRollPitch, 2),
              -2.0 * std::log(std::erfc(5.0 / std::sqrt(2.0))), 1e-6);
  // 3 dof: 1 - p = erfc(sqrt(x/2)) + sqrt(2x/π) e^{-x/2} solved by bisection in Python's
  // math module (independent of chi_square.cpp): 31.8121083486.
  EXPECT_NEAR(gate.chi2_gate(AidKind::kDvl, 3), 31.8121083486, 1e-6);
  AidGateOptions off;
  off.depth_sigma = 0.0;
  EXPECT_EQ(AidGate(off).chi2_gate(AidKind::kDepth, 1), 0.0);
  AidGateOptions bad;
  bad.heading_sigma = -1.0;
  EXPECT_THROW(AidGate{bad}, std::invalid_argument);
  bad = AidGateOptions{};
  bad.reset_timeout_s = -2.0;
  EXPECT_THROW(AidGate{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace nav::core
