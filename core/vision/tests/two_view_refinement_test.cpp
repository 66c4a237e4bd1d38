// Tests of two_view_refinement.h on synthetic scenes with known truth (synthetic_two_view.h:
// seafloor points around 3.5 m, 1280x1024 camera with fx = fy = 1000, pixel noise 0.5 px):
//  - the refinement recovers z within its covariance;
//  - the 5x5 covariance against a Monte Carlo of 300 noisy trials (NEES mean near 5, sample
//    covariance) and against the dense inverse of the full information with the points, built
//    from a numeric Jacobian of the residuals;
//  - robust loss against gross mismatches;
//  - degenerate inputs (too few matches, pure rotation, points behind the cameras, a failed
//    essential estimate) fail with a reason.

#include "nav/vision/two_view_refinement.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iostream>
#include <numbers>
#include <random>
#include <utility>

#include "dense_two_view.h"
#include "nav/core/geometry/rotation.h"
#include "nav/vision/relative_pose_5dof.h"
#include "synthetic_two_view.h"

namespace nav::vision {
namespace {

using test::deg;

constexpr double kSigmaPx = 0.5;
constexpr double kPi = std::numbers::pi;

/// Initial pose: the truth with its rotation and baseline direction disturbed by ~2-3 deg
/// (what an essential-matrix estimate typically hands over).
void perturbed_initial(const Vec6& x, Eigen::Matrix3d& R0, Eigen::Vector3d& t0) {
  R0 = core::pose_rotation(x) *
       core::rotation_from_euler(Eigen::Vector3d(deg(1.5), deg(-1), deg(2)));
  t0 = (core::pose_translation(x).normalized() + Eigen::Vector3d(0.03, -0.04, 0.02)).normalized();
}

TwoViewRefinementOptions options() {
  TwoViewRefinementOptions o;
  o.pixel_sigma_px = kSigmaPx;
  return o;
}

/// A scene of n matches (generator seeded by seed) around the default pose, refined from the
/// perturbed start with options o.
struct RefinedScene {
  test::TwoViewScene scene;
  TwoViewRefinement refinement;
};
RefinedScene refine_scene(unsigned seed, int n, const TwoViewRefinementOptions& o) {
  std::mt19937 rng(seed);
  const Vec6 x = test::default_x_i_j();
  RefinedScene out{test::make_scene(rng, x, n, 3.5, 0.3, kSigmaPx), {}};
  Eigen::Matrix3d R0;
  Eigen::Vector3d t0;
  perturbed_initial(x, R0, t0);
  out.refinement = refine_two_view(out.scene.u_i, out.scene.u_j, out.scene.camera, R0, t0, o);
  return out;
}

double nees(const Vec5& z, const Mat5& covariance, const Vec5& z_true) {
  const Vec5 e = z_minus(z, z_true);
  return e.dot(covariance.ldlt().solve(e));
}

double nees(const TwoViewRefinement& r, const Vec5& z_true) {
  return nees(r.z, r.covariance, z_true);
}

TEST(TwoViewRefinement, RecoversZWithinItsCovariance) {
  std::mt19937 rng(1);
  const Vec6 x = test::default_x_i_j();
  const test::TwoViewScene s = test::make_scene(rng, x, 150, 3.5, 0.3, kSigmaPx);
  Eigen::Matrix3d R0;
  Eigen::Vector3d t0;
  perturbed_initial(x, R0, t0);
  const TwoViewRefinement r = refine_two_view(s.u_i, s.u_j, s.camera, R0, t0, options());
  ASSERT_TRUE(r.converged) << r.reason;
  const Vec5 z_true = z_from_relative_pose(x);
  std::cout << "z error [deg] " << (z_minus(r.z, z_true) * 180.0 / kPi).transpose()
            << "\nsigma   [deg] " << (r.covariance.diagonal().cwiseSqrt() * 180.0 / kPi).transpose()
            << "\niterations " << r.iterations << ", rms " << r.initial_rms_px << " -> "
            << r.reprojection_rms_px << " px\n";
  EXPECT_LT(nees(r, z_true), 20.5);  // chi2_5 at 0.999
  // Residual degrees of freedom: 4n - 3n - 5 = n - 5 of 4n components.
  const double expected_rms = kSigmaPx * std::sqrt((150.0 - 5.0) / (4.0 * 150.0));
  EXPECT_NEAR(r.reprojection_rms_px, expected_rms, 0.2 * expected_rms);
  EXPECT_NEAR(r.residual_sigma_px, kSigmaPx, 0.15 * kSigmaPx);
  // Parallax of a 0.74 m baseline at 3.5 m: ~12 deg, ~200 px at f = 1000 px.
  EXPECT_GT(r.median_parallax_px, 150.0);
  EXPECT_EQ(r.used_matches.size(), 150u);
  EXPECT_EQ(r.behind_camera, 0);
  // Depths in baseline units: truth / |t|.
  const double baseline = core::pose_translation(x).norm();
  for (std::size_t k = 0; k < s.size(); k += 15)
    EXPECT_NEAR(r.depths_i[k], s.points_i[k].z() / baseline, 0.05 * s.points_i[k].z() / baseline);
  // z, R and t agree with each other.
  EXPECT_LT((rotation_from_z(r.z) - r.R_i_j).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((baseline_direction(r.z[0], r.z[1]) - r.t_i_j_unit).norm(), 1e-12);
}

/// Three scene geometries, 100 independent noise draws each: the NEES of z under the
/// information's covariance averages 5 (its 99 % interval for 300 trials is about [4.5, 5.5])
/// and the sample covariance of the error matches the mean predicted covariance; the reported
/// covariance (with the reliability term) is larger, in every direction.
void expect_consistent_covariance(const Vec6& x, std::uint32_t seed, const char* what) {
  std::mt19937 rng(seed);
  const Vec5 z_true = z_from_relative_pose(x);
  std::normal_distribution<double> noise(0.0, kSigmaPx);
  const int scenes = 3, trials_per_scene = 100, trials = scenes * trials_per_scene;
  double nees_sum = 0.0;
  Mat5 sample = Mat5::Zero(), predicted = Mat5::Zero();
  int converged = 0;
  for (int scene = 0; scene < scenes; ++scene) {
    const test::TwoViewScene truth = test::make_scene(rng, x, 80, 3.5, 0.3, 0.0);
    for (int trial = 0; trial < trials_per_scene; ++trial) {
      std::vector<Eigen::Vector2d> u_i = truth.u_i_true, u_j = truth.u_j_true;
      for (auto& u : u_i) u += Eigen::Vector2d(noise(rng), noise(rng));
      for (auto& u : u_j) u += Eigen::Vector2d(noise(rng), noise(rng));
      Eigen::Matrix3d R0;
      Eigen::Vector3d t0;
      perturbed_initial(x, R0, t0);
      const TwoViewRefinement r = refine_two_view(u_i, u_j, truth.camera, R0, t0, options());
      if (!r.converged) continue;
      ++converged;
      const Vec5 e = z_minus(r.z, z_true);
      nees_sum += nees(r.z, r.information_covariance, z_true);
      sample += e * e.transpose();
      predicted += r.information_covariance;
      const Mat5 extra = r.covariance - r.information_covariance;
      EXPECT_GE(Eigen::SelfAdjointEigenSolver<Mat5>(extra).eigenvalues().minCoeff(),
                -1e-12 * r.covariance.norm());
    }
  }
  ASSERT_EQ(converged, trials) << what;
  const double mean_nees = nees_sum / trials;
  sample /= trials;
  predicted /= trials;
  std::cout << what << ": NEES over " << trials << " trials: " << mean_nees
            << "\nsample sigma    [deg] "
            << (sample.diagonal().cwiseSqrt() * 180.0 / kPi).transpose()
            << "\npredicted sigma [deg] "
            << (predicted.diagonal().cwiseSqrt() * 180.0 / kPi).transpose() << "\n";
  EXPECT_GT(mean_nees, 4.5) << what;
  EXPECT_LT(mean_nees, 5.5) << what;
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(std::sqrt(sample(k, k)), std::sqrt(predicted(k, k)),
                0.15 * std::sqrt(predicted(k, k)))
        << what << ", component " << k;
  }
}

TEST(TwoViewRefinement, CovarianceMatchesMonteCarloNees) {
  expect_consistent_covariance(test::default_x_i_j(), 2, "lateral baseline");
}

TEST(TwoViewRefinement, CovarianceMatchesMonteCarloNeesDescending) {
  // Baseline 66 deg down the optical axis (descending while moving): elevation near its pole.
  Vec6 x = test::default_x_i_j();
  x.head<3>() << 0.2, 0.1, 0.5;
  expect_consistent_covariance(x, 12, "descending baseline");
}

TEST(TwoViewRefinement, CovarianceEqualsDenseInverseOfFullInformation) {
  // Independent reference: central-difference Jacobian of the whitened residuals with
  // respect to [z; all points], H = J^T J, dense inverse, top-left 5x5.
  TwoViewRefinementOptions o = options();
  o.huber_threshold_sigma = 1e9;  // plain least squares: every weight 1
  const RefinedScene solved = refine_scene(3, 30, o);
  const test::TwoViewScene& s = solved.scene;
  const TwoViewRefinement& r = solved.refinement;
  ASSERT_TRUE(r.converged) << r.reason;
  const int n = static_cast<int>(r.points_i.size());
  const test::DenseTwoView dense = test::dense_two_view(r, s, kSigmaPx);
  const Eigen::MatrixXd& J = dense.J;
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::MatrixXd P = H.inverse();
  const Mat5 P_zz = P.topLeftCorner<5, 5>();
  // The a-posteriori factor, from the residuals at the solution: max(1, RSS / (n - 5)) in
  // whitened units (4n residuals, 3n + 5 unknowns).
  const double factor = std::max(1.0, dense.residuals.squaredNorm() / (n - 5));
  EXPECT_NEAR(r.covariance_scale, factor, 1e-9 * factor);
  const double rel = (factor * P_zz - r.information_covariance).norm() / (factor * P_zz.norm());
  std::cout << "covariance vs dense inverse: relative difference " << rel << "\n";
  EXPECT_LT(rel, 1e-4);
  // And the solution is a stationary point of the cost: the Newton decrement g^T H^-1 g
  // (the cost a further Gauss-Newton step would gain) is negligible against the cost.
  const Eigen::VectorXd g = J.transpose() * dense.residuals;
  EXPECT_LT(g.dot(P * g), 1e-8 * dense.residuals.squaredNorm());
}

/// The same scene refined with options() and with `change` applied to them; both converged
/// to the same z.
std::pair<TwoViewRefinement, TwoViewRefinement> refine_before_and_after(
    const std::function<void(TwoViewRefinementOptions&)>& change) {
  TwoViewRefinementOptions o = options();
  TwoViewRefinement before = refine_scene(8, 60, o).refinement;
  change(o);
  TwoViewRefinement after = refine_scene(8, 60, o).refinement;
  EXPECT_TRUE(before.converged && after.converged) << before.reason << after.reason;
  EXPECT_EQ(after.z, before.z);
  return {std::move(before), std::move(after)};
}

TEST(TwoViewRefinement, ResidualSigmaFactorMultipliesTheAPosterioriSigma) {
  // With k the covariance is the unit-k one times max(1, k^2 s_hat^2 / s^2) / max(1, s_hat^2 /
  // s^2); z and the residual sigma are unchanged.
  const auto [plain, scaled] =
      refine_before_and_after([](TwoViewRefinementOptions& o) { o.residual_sigma_factor = 3.0; });
  EXPECT_EQ(scaled.residual_sigma_px, plain.residual_sigma_px);
  const double ratio2 = std::pow(plain.residual_sigma_px / kSigmaPx, 2);
  const double expected = std::max(1.0, 9.0 * ratio2);
  EXPECT_GT(expected, std::max(1.0, ratio2)) << "the scene must put k s_hat above the floor";
  EXPECT_NEAR(scaled.covariance_scale, expected, 1e-12 * expected);
  EXPECT_LT((scaled.information_covariance * plain.covariance_scale -
             plain.information_covariance * expected)
                .norm(),
            1e-9 * (expected * plain.information_covariance.norm()));
}

TEST(TwoViewRefinement, ModelErrorAddsItsVarianceToEveryAngleAndChangesNothingElse) {
  const auto [plain, with_model] =
      refine_before_and_after([](TwoViewRefinementOptions& o) { o.model_sigma_rad = 0.001; });
  EXPECT_EQ(with_model.information_covariance, plain.information_covariance);
  EXPECT_LT((with_model.covariance - plain.covariance - 1e-6 * Mat5::Identity()).norm(),
            1e-12 * plain.covariance.norm());
}

TEST(TwoViewRefinement, GrossMismatchesRejected) {
  // 10 % of the matches moved 40 px in image j across the epipolar line: they are rejected, the
  // solution is within its covariance of the truth and much closer than the plain least-squares
  // one.
  std::mt19937 rng(4);
  const Vec6 x = test::default_x_i_j();
  test::TwoViewScene s = test::make_scene(rng, x, 150, 3.5, 0.3, kSigmaPx);
  // Moved across the epipolar line (a shift along it is a different depth, not a mismatch).
  const Eigen::Matrix3d R = core::pose_rotation(x);
  const Eigen::Vector3d t = core::pose_translation(x);
  for (std::size_t k = 0; k < s.size(); k += 10) {
    const Eigen::Vector2d along =
        (test::project(s.camera, R.transpose() * (1.1 * s.points_i[k] - t)) - s.u_j_true[k])
            .normalized();
    s.u_j[k] += 40.0 * Eigen::Vector2d(-along.y(), along.x());
  }
  Eigen::Matrix3d R0;
  Eigen::Vector3d t0;
  perturbed_initial(x, R0, t0);
  const Vec5 z_true = z_from_relative_pose(x);
  const TwoViewRefinement robust = refine_two_view(s.u_i, s.u_j, s.camera, R0, t0, options());
  TwoViewRefinementOptions plain = options();
  plain.huber_threshold_sigma = 1e9;
  const TwoViewRefinement ls = refine_two_view(s.u_i, s.u_j, s.camera, R0, t0, plain);
  ASSERT_TRUE(robust.converged) << robust.reason;
  ASSERT_TRUE(ls.converged) << ls.reason;
  const double e_robust = z_minus(robust.z, z_true).norm(), e_ls = z_minus(ls.z, z_true).norm();
  std::cout << "error with 10 % gross mismatches: Huber " << e_robust * 180 / kPi
            << " deg, least squares " << e_ls * 180 / kPi << " deg\n";
  EXPECT_LT(e_robust, 0.5 * e_ls);
  EXPECT_EQ(robust.rejected_outliers, 15);
  EXPECT_EQ(robust.used_matches.size(), 135u);
  for (const int k : robust.used_matches) EXPECT_NE(k % 10, 0) << "mismatch " << k << " kept";
  EXPECT_LT(nees(robust, z_true), 20.5);
}

// Features three times noisier than the configured sigma (a camera with more pixels per
// feature scale, a scene that moves): with the kink fixed at 3 configured sigmas good matches
// are rejected round after round; with the kink at the measured noise they are kept, the noise
// is measured within its sampling error, and the covariance (scaled by the a-posteriori sigma)
// is consistent over independent draws.
TEST(TwoViewRefinement, KinkFollowsTheMeasuredNoise) {
  constexpr double kTrueSigmaPx = 1.0;
  TwoViewRefinementOptions o = options();
  set_pixel_sigma_keeping_parallax_floor(o, 0.3);
  TwoViewRefinementOptions fixed = o;
  fixed.kink_at_measured_noise = false;

  std::mt19937 rng(21);
  const Vec6 x = test::default_x_i_j();
  const Vec5 z_true = z_from_relative_pose(x);
  Eigen::Matrix3d R0;
  Eigen::Vector3d t0;
  perturbed_initial(x, R0, t0);
  const test::TwoViewScene s = test::make_scene(rng, x, 150, 3.5, 0.3, kTrueSigmaPx);
  const TwoViewRefinement with_fixed = refine_two_view(s.u_i, s.u_j, s.camera, R0, t0, fixed);
  EXPECT_TRUE(!with_fixed.converged || with_fixed.rejected_outliers > 15)
      << with_fixed.rejected_outliers << " rejected";
  const TwoViewRefinement r = refine_two_view(s.u_i, s.u_j, s.camera, R0, t0, o);
  ASSERT_TRUE(r.converged) << r.reason;
  std::cout << "noise " << kTrueSigmaPx << " px, configured 0.3 px: fixed kink "
            << (with_fixed.converged ? "kept " + std::to_string(with_fixed.used_matches.size())
                                     : with_fixed.reason)
            << "; measured " << r.robust_sigma_px << " px, " << r.used_matches.size() << " kept\n";
  EXPECT_NEAR(r.robust_sigma_px, kTrueSigmaPx, 0.2 * kTrueSigmaPx);  // sd ~10 % at 150
  // 3-sigma tails of 150 matches; the covariance scaled by (s_hat / 0.3)^2, s_hat near 1 px.
  EXPECT_GE(r.used_matches.size(), 147u);
  EXPECT_GT(r.covariance_scale, 8.0);

  std::normal_distribution<double> noise(0.0, kTrueSigmaPx);
  const test::TwoViewScene truth = test::make_scene(rng, x, 80, 3.5, 0.3, 0.0);
  double nees_sum = 0.0, sigma_sum = 0.0;
  const int trials = 100;
  for (int trial = 0; trial < trials; ++trial) {
    std::vector<Eigen::Vector2d> u_i = truth.u_i_true, u_j = truth.u_j_true;
    for (auto& u : u_i) u += Eigen::Vector2d(noise(rng), noise(rng));
    for (auto& u : u_j) u += Eigen::Vector2d(noise(rng), noise(rng));
    const TwoViewRefinement t = refine_two_view(u_i, u_j, truth.camera, R0, t0, o);
    ASSERT_TRUE(t.converged) << "trial " << trial << ": " << t.reason;
    nees_sum += nees(t, z_true);
    sigma_sum += t.robust_sigma_px;
  }
  std::cout << "over " << trials << " draws: NEES mean " << nees_sum / trials
            << ", measured noise mean " << sigma_sum / trials << " px\n";
  EXPECT_NEAR(sigma_sum / trials, kTrueSigmaPx, 0.05 * kTrueSigmaPx);
  EXPECT_GT(nees_sum / trials, 4.0);
  EXPECT_LT(nees_sum / trials, 6.5);
}

TEST(TwoViewRefinement, TooFewMatchesFail) {
  std::mt19937 rng(5);
  const Vec6 x = test::default_x_i_j();
  const test::TwoViewScene s = test::make_scene(rng, x, 5, 3.5, 0.3, kSigmaPx);
  const TwoViewRefinement r = refine_two_view(s.u_i, s.u_j, s.camera, core::pose_rotation(x),
                                              core::pose_translation(x), options());
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.reason.find("fewer than the 8 needed"), std::string::npos) << r.reason;
}

TEST(TwoViewRefinement, PureRotationFails) {
  // Zero baseline: image j is a pure rotation of image i. Any initial baseline direction.
  std::mt19937 rng(6);
  Vec6 x = test::default_x_i_j();
  x.head<3>().setZero();
  const test::TwoViewScene s = test::make_scene(rng, x, 100, 3.5, 0.3, kSigmaPx);
  const TwoViewRefinement r = refine_two_view(s.u_i, s.u_j, s.camera, core::pose_rotation(x),
                                              Eigen::Vector3d(1.0, 0.3, 0.0), options());
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.reason.find("pure rotation"), std::string::npos) << r.reason;
}

TEST(TwoViewRefinement, ShortBaselineRegistersNoiseLevelParallaxFails) {
  // 5 cm at 3.5 m (~14 px of parallax) is a usable, if weak, baseline: z within its
  // covariance. 2 mm (~0.6 px, near the 0.5 px noise) cannot be told from a pure rotation.
  std::mt19937 rng(9);
  Vec6 x = test::default_x_i_j();
  x.head<3>() = x.head<3>().normalized() * 0.05;
  const test::TwoViewScene s = test::make_scene(rng, x, 150, 3.5, 0.3, kSigmaPx);
  const TwoViewRefinement r = refine_two_view(s.u_i, s.u_j, s.camera, core::pose_rotation(x),
                                              core::pose_translation(x), options());
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_LT(nees(r, z_from_relative_pose(x)), 20.5);
  x.head<3>() = x.head<3>().normalized() * 0.002;
  const test::TwoViewScene tiny = test::make_scene(rng, x, 150, 3.5, 0.3, kSigmaPx);
  const TwoViewRefinement t =
      refine_two_view(tiny.u_i, tiny.u_j, tiny.camera, core::pose_rotation(x),
                      core::pose_translation(x), options());
  EXPECT_FALSE(t.converged);
  EXPECT_NE(t.reason.find("pure rotation"), std::string::npos) << t.reason;
}

TEST(TwoViewRefinement, PointsBehindTheCamerasFail) {
  // The mirrored baseline (-t, the wrong one of the four essential decompositions) puts the
  // points behind both cameras.
  std::mt19937 rng(7);
  const Vec6 x = test::default_x_i_j();
  const test::TwoViewScene s = test::make_scene(rng, x, 100, 3.5, 0.3, kSigmaPx);
  const TwoViewRefinement r = refine_two_view(s.u_i, s.u_j, s.camera, core::pose_rotation(x),
                                              -core::pose_translation(x), options());
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.reason.find("behind camera"), std::string::npos) << r.reason;
  EXPECT_GT(r.behind_camera, 50);
}

TEST(TwoViewRefinement, FromEssentialEstimateMapsMatchIndices) {
  std::mt19937 rng(8);
  const Vec6 x = test::default_x_i_j();
  const test::TwoViewScene s = test::make_scene(rng, x, 60, 3.5, 0.3, kSigmaPx);
  ImageFeatures fi, fj;
  fi.points_px = s.u_i;
  // Image j's features in reverse order; matches list every pair plus one bogus first entry.
  fj.points_px.assign(s.u_j.rbegin(), s.u_j.rend());
  PutativeMatches matches;
  matches.matches.push_back({0, 0, 0.0f});
  EssentialEstimate e;
  e.ok = true;
  perturbed_initial(x, e.R_i_j, e.t_i_j_unit);
  for (int k = 0; k < 60; ++k) {
    matches.matches.push_back({k, 59 - k, 0.0f});
    e.inliers.push_back(k + 1);
  }
  const TwoViewRefinement r = refine_two_view(fi, fj, matches, e, s.camera, options());
  ASSERT_TRUE(r.converged) << r.reason;
  ASSERT_EQ(r.used_matches.size(), 60u);
  EXPECT_EQ(r.used_matches.front(), 1);
  EXPECT_EQ(r.used_matches.back(), 60);
  EXPECT_LT(nees(r, z_from_relative_pose(x)), 20.5);

  e.inliers.push_back(99);  // names no match
  EXPECT_NE(refine_two_view(fi, fj, matches, e, s.camera, options()).reason.find("inlier 99"),
            std::string::npos);
  e.ok = false;
  e.reason = "LMedS found no model";
  const TwoViewRefinement bad = refine_two_view(fi, fj, matches, e, s.camera, options());
  EXPECT_FALSE(bad.converged);
  EXPECT_NE(bad.reason.find("LMedS found no model"), std::string::npos) << bad.reason;
}

}  // namespace
}  // namespace nav::vision
