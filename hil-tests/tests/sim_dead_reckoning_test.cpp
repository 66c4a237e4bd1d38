// Dead reckoning is the baseline of "SLAM against dead reckoning" (core/navigation/
// dead_reckoning.h: the robot alone, in covariance form). On a simulated dive, fed the log's
// measurements through the replay's dive-log source and decoders, in time order:
// * It estimates what the information filter without links estimates: at every image its robot
//   mean and covariance match a NavFilter that proposes no link and solves its delayed states
//   exactly at every image (a factor kept equal to Λ).
// * Its track is a property of the measurements, not of the rounding: one DVL velocity changed
//   in its 13th digit moves its final position by less than a micrometre. The same change moves
//   the information filter's (printed, docs/consistency.md "The dead-reckoning baseline").
// * Its final XY error lies inside its covariance's 99.9 % ellipse.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <variant>
#include <vector>

#include "nav/core/navigation/chi_square.h"
#include "nav/core/navigation/dead_reckoning.h"
#include "nav/daemon/replay/dive_replay.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

/// The information filter without links, its delayed states solved exactly at every image.
core::NavFilterOptions information_form_reference(core::NavFilterOptions o) {
  o.propose_links = false;
  o.recovery_thread = false;
  o.recovery.preconditioner = core::RecoveryPreconditioner::kFactor;
  o.recovery.keep_factor_equal = true;
  o.recovery.refresh_interval = std::numeric_limits<int>::max();
  return o;
}

/// The same measurements with the first DVL velocity's surge scaled by (1 + relative).
std::vector<daemon::Measurement> with_one_dvl_changed(std::vector<daemon::Measurement> ms,
                                                      double relative) {
  for (daemon::Measurement& m : ms) {
    if (auto* dvl = std::get_if<core::DvlVelocity>(&m)) {
      dvl->v_sensor_mps[0] *= 1.0 + relative;
      break;
    }
  }
  return ms;
}

template <class Filter>
Filter run_filter(Filter f, const std::vector<daemon::Measurement>& ms) {
  for (const daemon::Measurement& m : ms) EXPECT_TRUE(f.process(m).ok());
  return f;
}

TEST(SimDeadReckoning, IsTheFilterWithoutLinksFreeOfRoundingAndInsideItsCovariance) {
  const auto dir = scratch_dir("dead_reckoning");
  simulate_dive(sim_options(dir, 5, 100), sim_config_path().string());
  const daemon::NavdConfig cfg = daemon::load_config_file((dir / "config.yaml").string());
  const std::vector<daemon::Measurement> ms =
      time_ordered_measurements((dir / "dive.lcmlog").string(), cfg);
  const core::NavFilterOptions options = daemon::filter_options_from_config(cfg);

  const core::DeadReckoningFilter dr = run_filter(core::DeadReckoningFilter(options), ms);
  core::NavFilter reference(information_form_reference(options), nullptr);
  for (const daemon::Measurement& m : ms) ASSERT_TRUE(reference.process(m).ok());
  ASSERT_EQ(dr.images().size(), 100u);
  ASSERT_EQ(reference.images().size(), 100u);
  // The two differ by where the aids are linearised (the information form: at the prediction's
  // mean, for every aid until the next prediction) and by the information form's rounding,
  // which grows with the chain (the last bullet of the file comment).
  constexpr std::size_t kSettledImages = 60;  // before the dive's first DVL outage
  struct Worst {
    double sigmas = 0.0, variance = 0.0;
    void note(double s, double v) {
      sigmas = std::max(sigmas, s);
      variance = std::max(variance, v);
    }
  } early, all;
  for (std::size_t k = 0; k < dr.images().size(); ++k) {
    const core::ImageRecord& a = dr.images()[k];
    const core::ImageRecord& b = reference.images()[k];
    const Eigen::Vector2d va = a.robot_covariance.diagonal().head<2>();
    const Eigen::Vector2d vb = b.robot_covariance.diagonal().head<2>();
    const double sigmas =
        (a.robot_mean - b.robot_mean).head<2>().cwiseQuotient(va.cwiseSqrt()).cwiseAbs().maxCoeff();
    const double variance = (va - vb).cwiseQuotient(vb).cwiseAbs().maxCoeff();
    all.note(sigmas, variance);
    if (k < kSettledImages) early.note(sigmas, variance);
  }
  std::printf(
      "dead reckoning against the information form: XY means within %.3g sigma, XY "
      "variances within %.3g (relative); over the first %zu images %.3g sigma, %.3g\n",
      all.sigmas, all.variance, kSettledImages, early.sigmas, early.variance);
  EXPECT_LT(early.sigmas, 0.05);
  EXPECT_LT(early.variance, 1e-3);
  EXPECT_LT(all.sigmas, 0.25);
  EXPECT_LT(all.variance, 1e-2);

  const std::vector<daemon::Measurement> changed = with_one_dvl_changed(ms, 1e-12);
  const core::DeadReckoningFilter dr_changed =
      run_filter(core::DeadReckoningFilter(options), changed);
  core::NavFilter reference_changed(information_form_reference(options), nullptr);
  for (const daemon::Measurement& m : changed) ASSERT_TRUE(reference_changed.process(m).ok());
  const double moved_m =
      (dr.images().back().robot_mean - dr_changed.images().back().robot_mean).head<2>().norm();
  const double reference_moved_m =
      (reference.images().back().robot_mean - reference_changed.images().back().robot_mean)
          .head<2>()
          .norm();
  std::printf(
      "one DVL velocity changed by 1e-12 (relative) moves the final XY by %.3g m "
      "(the information form's by %.3g m)\n",
      moved_m, reference_moved_m);
  EXPECT_LT(moved_m, 1e-6);

  const auto images = read_csv(dir / "images.csv");  // frame_id,t_us,x,y,...
  const core::ImageRecord& last = dr.images().back();
  const auto& truth = images.at(last.frame_id);
  const Eigen::Vector2d e(last.robot_mean[0] - truth[2], last.robot_mean[1] - truth[3]);
  const double nees2 = e.dot(last.robot_covariance.topLeftCorner<2, 2>().ldlt().solve(e));
  std::printf("dead reckoning: final XY error %.3f m, NEES %.2f (2 dof)\n", e.norm(), nees2);
  EXPECT_LT(nees2, core::chi_square_quantile(0.999, 2));
}

}  // namespace
}  // namespace nav::sim::test
