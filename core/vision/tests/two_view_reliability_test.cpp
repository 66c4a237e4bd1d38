// Tests of the reliability term of the two-view covariance (two_view_refinement.h) against an
// independent dense reference: the full whitened Jacobian J of the residuals in (z, all
// points) by central differences, the hat matrix J H^-1 J^T (H = J^T J) and the redundancy
// matrix R = I - J H^-1 J^T. A blunder b in the residuals of the matches G shifts the
// estimate by P_G b, P = (H^-1 J^T) restricted to z's rows and G's columns, and the test on
// the residuals sees the non-centrality b^T R_GG b. The largest shifts with b^T R_GG b <=
// delta0^2 fill the ellipsoid delta0^2 P_G R_GG^+ P_G^T (Foerstner, CVGIP 40(3), 1987), which
// the refinement's reliability_covariance must equal (times the a-posteriori factor).

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <iostream>
#include <random>
#include <vector>

#include "dense_two_view.h"
#include "nav/vision/relative_pose_5dof.h"
#include "nav/vision/two_view_refinement.h"
#include "synthetic_two_view.h"

namespace nav::vision {
namespace {

constexpr double kSigmaPx = 0.5;
constexpr double kDelta0 = 4.13;  // Baarda: 0.1 % two-sided test, 80 % power

struct DenseProblem {
  Eigen::MatrixXd P_z;  ///< rows of z in H^-1 J^T: the estimate's response to the residuals
  Eigen::MatrixXd R;    ///< redundancy matrix I - J H^-1 J^T
  Mat5 C;               ///< top-left 5x5 block of H^-1
  double factor = 1.0;  ///< a-posteriori variance factor max(1, RSS / (n - 5))
};

DenseProblem dense_problem(const TwoViewRefinement& r, const test::TwoViewScene& s) {
  const int n = static_cast<int>(r.points_i.size());
  const test::DenseTwoView dense = test::dense_two_view(r, s, kSigmaPx);
  const Eigen::MatrixXd& J = dense.J;
  const Eigen::MatrixXd H_inv = (J.transpose() * J).inverse();
  DenseProblem d;
  d.P_z = (H_inv * J.transpose()).topRows(5);
  d.R = Eigen::MatrixXd::Identity(J.rows(), J.rows()) - J * H_inv * J.transpose();
  d.C = H_inv.topLeftCorner<5, 5>();
  d.factor = std::max(1.0, dense.residuals.squaredNorm() / (n - 5));
  return d;
}

/// delta0^2 P_G R_GG^+ P_G^T for the matches G (4 residual rows each: u_i, u_j).
Mat5 dense_bound(const DenseProblem& d, const std::vector<int>& group, double delta0) {
  const int g = static_cast<int>(group.size());
  Eigen::MatrixXd P(5, 4 * g), R(4 * g, 4 * g);
  for (int a = 0; a < g; ++a) {
    P.middleCols(4 * a, 4) = d.P_z.middleCols(4 * group[a], 4);
    for (int b = 0; b < g; ++b)
      R.block(4 * a, 4 * b, 4, 4) = d.R.block(4 * group[a], 4 * group[b], 4, 4);
  }
  // R_GG has rank g: each match's own point absorbs 3 of its 4 residual directions.
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  svd.setThreshold(1e-6);
  EXPECT_EQ(svd.rank(), g);
  return delta0 * delta0 * P * svd.solve(P.transpose());
}

struct Case {
  test::TwoViewScene scene;
  TwoViewRefinement r;
};

/// Few matches (14, noisy, depth 3.5 m): leverages well above the 5 / n average.
Case weak_case(int group, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const Vec6 x = test::default_x_i_j();
  Case c;
  c.scene = test::make_scene(rng, x, 14, 3.5, 0.3, kSigmaPx);
  TwoViewRefinementOptions o;
  o.pixel_sigma_px = kSigmaPx;
  o.huber_threshold_sigma = 1e9;  // plain least squares: every weight 1, every match kept
  o.reliability_delta0 = kDelta0;
  o.reliability_group = group;
  c.r = refine_two_view(c.scene.u_i, c.scene.u_j, c.scene.camera, core::pose_rotation(x),
                        core::pose_translation(x), o);
  return c;
}

double relative_difference(const Mat5& a, const Mat5& b) { return (a - b).norm() / b.norm(); }

TEST(TwoViewReliability, SingleMatchBoundEqualsDenseReferenceAndTakesTheLargestShift) {
  const Case c = weak_case(1, 21);
  ASSERT_TRUE(c.r.converged) << c.r.reason;
  ASSERT_EQ(c.r.reliability_matches.size(), 1u);
  const DenseProblem d = dense_problem(c.r, c.scene);
  const Mat5 expected = d.factor * dense_bound(d, c.r.reliability_matches, kDelta0);
  const double rel = relative_difference(c.r.reliability_covariance, expected);
  std::cout << "single-match bound vs dense: relative difference " << rel << ", max leverage "
            << c.r.max_leverage << "\n";
  EXPECT_LT(rel, 1e-4);
  // The chosen match has the largest shift (Mahalanobis size trace(C^-1 bound)) of all.
  const Eigen::LDLT<Mat5> C(d.C);
  const double chosen = C.solve(expected / d.factor).trace();
  for (int k = 0; k < static_cast<int>(c.r.used_matches.size()); ++k)
    EXPECT_LE(C.solve(dense_bound(d, {k}, kDelta0)).trace(), chosen * (1 + 1e-6)) << "match " << k;
  EXPECT_NEAR(c.r.covariance.norm(),
              (c.r.information_covariance + c.r.reliability_covariance).norm(), 1e-12);
}

TEST(TwoViewReliability, GroupBoundEqualsDenseReference) {
  for (const int group : {2, 3}) {
    const Case c = weak_case(group, 22);
    ASSERT_TRUE(c.r.converged) << c.r.reason;
    ASSERT_EQ(static_cast<int>(c.r.reliability_matches.size()), group);
    const DenseProblem d = dense_problem(c.r, c.scene);
    const Mat5 expected = d.factor * dense_bound(d, c.r.reliability_matches, kDelta0);
    EXPECT_LT(relative_difference(c.r.reliability_covariance, expected), 1e-4) << group;
  }
}

TEST(TwoViewReliability, ZeroNonCentralityLeavesTheInformationAlone) {
  std::mt19937 rng(23);
  const Vec6 x = test::default_x_i_j();
  const test::TwoViewScene s = test::make_scene(rng, x, 40, 3.5, 0.3, kSigmaPx);
  TwoViewRefinementOptions o;
  o.pixel_sigma_px = kSigmaPx;
  o.reliability_delta0 = 0.0;
  const TwoViewRefinement r =
      refine_two_view(s.u_i, s.u_j, s.camera, core::pose_rotation(x), core::pose_translation(x), o);
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_TRUE(r.reliability_matches.empty());
  EXPECT_EQ(r.reliability_covariance, Mat5::Zero());
  EXPECT_EQ(r.covariance, r.information_covariance);
  EXPECT_GT(r.max_leverage, 0.0);
  EXPECT_LT(r.max_leverage, 1.0);
}

}  // namespace
}  // namespace nav::vision
