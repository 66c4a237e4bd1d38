// Tests of validation.h: the chi2(5) tail against tabulated values, a sound synthetic
// registration passing with its chi2 against the prior distributed as chi2(5) over a Monte
// Carlo, and every check failing with its code and a reason that names the numbers.

#include "nav/vision/validation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>
#include <stdexcept>

#include "nav/vision/relative_pose_5dof.h"
#include "synthetic_two_view.h"

namespace nav::vision {
namespace {

using test::deg;

constexpr double kSigmaPx = 0.5;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

RelativePosePrior prior_at(const Vec6& mean) {
  RelativePosePrior p;
  p.x_i_j = mean;
  p.covariance = test::default_prior_covariance();
  p.scene_depth_m = 3.5;
  p.scene_depth_sigma_m = 0.3;
  return p;
}

TwoViewRefinement refined(std::mt19937& rng, const Vec6& x, int n = 100) {
  const test::TwoViewScene s = test::make_scene(rng, x, n, 3.5, 0.3, kSigmaPx);
  TwoViewRefinementOptions o;
  o.pixel_sigma_px = kSigmaPx;
  return refine_two_view(s.u_i, s.u_j, s.camera, core::pose_rotation(x), core::pose_translation(x),
                         o);
}

TEST(Validation, Chi2FiveTailMatchesTables) {
  // Quantiles of chi2 with 5 degrees of freedom (Abramowitz & Stegun, table 26.8).
  EXPECT_NEAR(chi2_5_survival(11.0705), 0.05, 1e-5);
  EXPECT_NEAR(chi2_5_survival(15.0863), 0.01, 1e-5);
  EXPECT_NEAR(chi2_5_survival(20.5150), 0.001, 1e-6);
  EXPECT_NEAR(chi2_5_survival(4.35146), 0.5, 1e-5);
  EXPECT_NEAR(chi2_5_quantile(0.999), 20.5150, 1e-3);
  EXPECT_DOUBLE_EQ(chi2_5_survival(0.0), 1.0);
  EXPECT_THROW(chi2_5_quantile(1.0), std::invalid_argument);
}

TEST(Validation, SoundRegistrationPassesWithChi2AgainstThePrior) {
  // Truth drawn from the prior: over 200 registrations the reported chi2 averages 5.
  std::mt19937 rng(1);
  const Mat6 P = test::default_prior_covariance();
  double chi2_sum = 0.0;
  const int trials = 200;
  for (int k = 0; k < trials; ++k) {
    const Vec6 x = test::default_x_i_j();
    const RelativePosePrior prior = prior_at(x - test::draw(rng, P));
    const TwoViewRefinement r = refined(rng, x);
    RegistrationResult result;
    validate_registration(r, &prior, ValidationOptions{}, result);
    ASSERT_TRUE(result.success) << result.reason;
    EXPECT_EQ(result.failure, RegistrationFailure::kOk);
    EXPECT_TRUE(result.reason.empty());
    EXPECT_EQ(result.inliers, static_cast<int>(r.used_matches.size()));
    EXPECT_EQ(result.z, r.z);
    chi2_sum += result.prior_chi2;
  }
  const double mean = chi2_sum / trials;
  std::cout << "mean chi2(5) of z against the prior over " << trials << " trials: " << mean << "\n";
  EXPECT_GT(mean, 4.2);
  EXPECT_LT(mean, 5.9);
}

TEST(Validation, WithoutPriorNoChi2) {
  std::mt19937 rng(2);
  RegistrationResult result;
  validate_registration(refined(rng, test::default_x_i_j()), nullptr, ValidationOptions{}, result);
  EXPECT_TRUE(result.success) << result.reason;
  EXPECT_EQ(result.prior_chi2, -1.0);
}

TEST(Validation, RefinementFailureKeepsItsCodeAndReason) {
  std::mt19937 rng(3);
  const TwoViewRefinement r = refined(rng, test::default_x_i_j(), 5);
  ASSERT_FALSE(r.converged);
  RegistrationResult result;
  validate_registration(r, nullptr, ValidationOptions{}, result);
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.failure, RegistrationFailure::kTooFewInliers);
  EXPECT_EQ(result.reason, r.reason);
  TwoViewRefinement not_converged;
  not_converged.reason = "no convergence";
  validate_registration(not_converged, nullptr, ValidationOptions{}, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kRefinementFailed);
}

TEST(Validation, EachCheckFailsWithItsCode) {
  std::mt19937 rng(4);
  const Vec6 x = test::default_x_i_j();
  const TwoViewRefinement good = refined(rng, x);
  ASSERT_TRUE(good.converged) << good.reason;
  const RelativePosePrior prior = prior_at(x);
  RegistrationResult result;

  ValidationOptions strict;
  strict.min_inliers = 500;
  validate_registration(good, &prior, strict, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kTooFewInliers);
  EXPECT_TRUE(contains(result.reason, "fewer than the 500")) << result.reason;

  // Matches uniform over the frame spread over ~1 of it; a cluster on one patch fails.
  EXPECT_GT(good.inlier_area_fraction, 0.6);
  strict = ValidationOptions{};
  strict.min_inlier_area_fraction = 1.5 * good.inlier_area_fraction;
  validate_registration(good, &prior, strict, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kTooFewInliers);
  EXPECT_TRUE(contains(result.reason, "of the frame (second-moment area)")) << result.reason;
  std::mt19937 rng_cluster(5);
  const test::TwoViewScene wide = test::make_scene(rng_cluster, x, 2000, 3.5, 0.3, kSigmaPx);
  std::vector<Eigen::Vector2d> u_i, u_j;  // the matches of one 200 x 200 px patch of image i
  for (std::size_t k = 0; k < wide.size(); ++k) {
    const Eigen::Vector2d d = wide.u_i[k] - Eigen::Vector2d(wide.camera.cx_px, wide.camera.cy_px);
    if (d.cwiseAbs().maxCoeff() < 100.0) {
      u_i.push_back(wide.u_i[k]);
      u_j.push_back(wide.u_j[k]);
    }
  }
  TwoViewRefinementOptions o;
  o.pixel_sigma_px = kSigmaPx;
  const TwoViewRefinement cluster = refine_two_view(
      u_i, u_j, wide.camera, core::pose_rotation(x), core::pose_translation(x), o);
  ASSERT_TRUE(cluster.converged) << cluster.reason;
  // Uniform over a 200 x 200 px square: 40,000 px^2 of the frame.
  const double square = 40000.0 / (wide.camera.width_px * wide.camera.height_px);
  EXPECT_NEAR(cluster.inlier_area_fraction, square, 0.35 * square);
  validate_registration(cluster, &prior, ValidationOptions{}, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kTooFewInliers) << cluster.inlier_area_fraction;

  strict = ValidationOptions{};
  strict.max_reprojection_rms_px = 0.1;
  validate_registration(good, &prior, strict, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kReprojectionError);
  EXPECT_TRUE(contains(result.reason, "above the limit 0.1 px")) << result.reason;

  TwoViewRefinement behind = good;
  behind.depths_j[7] = -0.5;
  validate_registration(behind, &prior, ValidationOptions{}, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kRefinementFailed);
  EXPECT_TRUE(contains(result.reason, "1 behind camera j")) << result.reason;

  // The prior puts the seafloor at 10 m: the triangulated 3.5 m is out of it.
  RelativePosePrior deep = prior;
  deep.scene_depth_m = 10.0;
  validate_registration(good, &deep, ValidationOptions{}, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kDepthOutOfPrior);
  EXPECT_TRUE(contains(result.reason, "scene-depth prior 10")) << result.reason;
  // A baseline prior twice the truth scales every depth to 7 m: also out.
  RelativePosePrior long_baseline = prior;
  long_baseline.x_i_j.head<3>() *= 2.0;
  validate_registration(good, &long_baseline, ValidationOptions{}, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kDepthOutOfPrior);

  // Heading prior 10 deg off with a 0.5 deg sigma: chi2 large, reported; fails only gated.
  RelativePosePrior off = prior;
  off.x_i_j[5] += deg(10.0);
  off.covariance(5, 5) = deg(0.5) * deg(0.5);
  validate_registration(good, &off, ValidationOptions{}, result);
  EXPECT_TRUE(result.success) << result.reason;
  EXPECT_GT(result.prior_chi2, 100.0);
  ValidationOptions gated;
  gated.gate_prior_chi2 = true;
  validate_registration(good, &off, gated, result);
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.failure, RegistrationFailure::kRefinementFailed);
  EXPECT_TRUE(contains(result.reason, "disagrees with the prior")) << result.reason;

  // A prior without a horizontal baseline predicts no azimuth.
  RelativePosePrior vertical = prior;
  vertical.x_i_j.head<3>() << 0.0, 0.0, 0.5;
  validate_registration(good, &vertical, ValidationOptions{}, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kRefinementFailed);
  EXPECT_TRUE(contains(result.reason, "prior unusable")) << result.reason;
}

TEST(Validation, AMatchThatDecidesAPoseDirectionAloneFails) {
  // The matches of one 120 x 120 px patch at the centre plus one far in a corner: the corner
  // match alone pins the rotation about the optical axis, so its leverage is near 1, while
  // every match of a scene spread over the frame has a small one (leverages sum to 5).
  std::mt19937 rng(6);
  const Vec6 x = test::default_x_i_j();
  const TwoViewRefinement spread = refined(rng, x);
  ASSERT_TRUE(spread.converged) << spread.reason;
  EXPECT_LT(spread.max_leverage, 0.3);
  const test::TwoViewScene wide = test::make_scene(rng, x, 4000, 3.5, 0.3, kSigmaPx);
  std::vector<Eigen::Vector2d> u_i, u_j;
  double corner_distance = 0.0;
  std::size_t corner = 0;
  for (std::size_t k = 0; k < wide.size(); ++k) {
    const Eigen::Vector2d d = wide.u_i[k] - Eigen::Vector2d(wide.camera.cx_px, wide.camera.cy_px);
    if (d.cwiseAbs().maxCoeff() < 60.0) {
      u_i.push_back(wide.u_i[k]);
      u_j.push_back(wide.u_j[k]);
    }
    if (d.norm() > corner_distance) corner_distance = d.norm(), corner = k;
  }
  u_i.push_back(wide.u_i[corner]);
  u_j.push_back(wide.u_j[corner]);
  TwoViewRefinementOptions o;
  o.pixel_sigma_px = kSigmaPx;
  const TwoViewRefinement lone =
      refine_two_view(u_i, u_j, wide.camera, core::pose_rotation(x), core::pose_translation(x), o);
  ASSERT_TRUE(lone.converged) << lone.reason;
  EXPECT_GT(lone.max_leverage, 0.8) << u_i.size() << " matches";

  const RelativePosePrior prior = prior_at(x);
  ValidationOptions strict;
  strict.min_inlier_area_fraction = 0.0;
  strict.max_leverage = 0.8;
  RegistrationResult result;
  validate_registration(spread, &prior, strict, result);
  EXPECT_TRUE(result.success) << result.reason;
  validate_registration(lone, &prior, strict, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kTooFewInliers);
  EXPECT_TRUE(contains(result.reason, "decides a direction of the pose alone")) << result.reason;
  // The default accepts it (leverage is at most 1).
  validate_registration(lone, &prior, ValidationOptions{.min_inlier_area_fraction = 0.0}, result);
  EXPECT_NE(result.failure, RegistrationFailure::kTooFewInliers) << result.reason;
}

TEST(Validation, ARegistrationTooUncertainToBeAMeasurementFails) {
  // The same geometry seen through 14 matches instead of 200: wider sigmas. A limit between
  // the two widest sigmas passes the strong registration and refuses the weak one, naming the
  // widest angle, unless the weak one has uncertain_min_inliers inliers.
  std::mt19937 rng(7);
  const Vec6 x = test::default_x_i_j();
  const TwoViewRefinement strong = refined(rng, x, 200);
  const TwoViewRefinement weak = refined(rng, x, 14);
  ASSERT_TRUE(strong.converged && weak.converged) << strong.reason << weak.reason;
  Eigen::Index widest = 0;
  const double sigma_weak = weak.covariance.diagonal().cwiseSqrt().maxCoeff(&widest);
  const double sigma_strong = strong.covariance.diagonal().cwiseSqrt().maxCoeff();
  ASSERT_GT(sigma_weak, 2.0 * sigma_strong);
  const char* names[] = {"azimuth", "elevation", "roll", "pitch", "heading"};

  const RelativePosePrior prior = prior_at(x);
  ValidationOptions limit;
  limit.max_sigma_rad = std::sqrt(sigma_weak * sigma_strong);
  RegistrationResult result;
  validate_registration(strong, &prior, limit, result);
  EXPECT_TRUE(result.success) << result.reason;
  validate_registration(weak, &prior, limit, result);
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.failure, RegistrationFailure::kTooUncertain);
  EXPECT_TRUE(contains(result.reason, std::string("the ") + names[widest] + " sigma"))
      << result.reason;
  EXPECT_TRUE(contains(result.reason, "(" + std::to_string(weak.used_matches.size()) + " inliers)"))
      << result.reason;
  EXPECT_TRUE(contains(result.reason, "fewer than")) << result.reason;
  const int weak_inliers = static_cast<int>(weak.used_matches.size());
  limit.uncertain_min_inliers = weak_inliers + 1;
  validate_registration(weak, &prior, limit, result);
  EXPECT_EQ(result.failure, RegistrationFailure::kTooUncertain) << result.reason;
  limit.uncertain_min_inliers = weak_inliers;
  validate_registration(weak, &prior, limit, result);
  EXPECT_NE(result.failure, RegistrationFailure::kTooUncertain) << result.reason;
  // Without a limit (the struct's default) the weak registration passes this check.
  validate_registration(weak, &prior, ValidationOptions{}, result);
  EXPECT_NE(result.failure, RegistrationFailure::kTooUncertain) << result.reason;
}

TEST(Validation, FailureNames) {
  EXPECT_EQ(failure_name(RegistrationFailure::kTooUncertain), "too uncertain");
  EXPECT_EQ(failure_name(RegistrationFailure::kDepthOutOfPrior), "depth out of prior");
  EXPECT_EQ(failure_name(RegistrationFailure::kOk), "ok");
}

}  // namespace
}  // namespace nav::vision
