// Tests of the systematic-displacement term of the two-view covariance (two_view_refinement.h,
// systematic_*) against an independent dense reference: the full whitened Jacobian J of the
// residuals in (z, all points) by central differences gives the estimate's first-order response
// P_z = rows of z in (J^T J)^-1 J^T to a residual perturbation. A displacement field d(u) =
// Phi(u) b in the two images perturbs the whitened residuals by M b (M: Phi at each match's
// pixel, divided by the pixel sigma), so the consider covariance of coefficients of sigma each
// is sigma^2 (P_z M)(P_z M)^T. Phi is the contract of two_view_problem.h, written out here
// again: the monomials 1, x, y, x^2, xy, y^2 per axis of the pixel offset from the principal
// point divided by the image's largest offset of a used point along that axis.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "dense_two_view.h"
#include "nav/vision/two_view_refinement.h"
#include "synthetic_two_view.h"

namespace nav::vision {
namespace {

constexpr double kSigmaPx = 0.5;

/// Rows [2k, 2k+1] of the field's 12-coefficient basis at the points u (one image).
Eigen::MatrixXd field_basis(const std::vector<Eigen::Vector2d>& u, const CameraIntrinsics& c) {
  const Eigen::Vector2d centre(c.cx_px, c.cy_px);
  Eigen::Vector2d extent(1.0, 1.0);
  for (const auto& p : u) extent = extent.cwiseMax((p - centre).cwiseAbs());
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Zero(2 * static_cast<Eigen::Index>(u.size()), 12);
  for (std::size_t k = 0; k < u.size(); ++k) {
    const double x = (u[k].x() - centre.x()) / extent.x(), y = (u[k].y() - centre.y()) / extent.y();
    const double m[6] = {1.0, x, y, x * x, x * y, y * y};
    for (int t = 0; t < 6; ++t) {
      Phi(2 * static_cast<Eigen::Index>(k), t) = m[t];
      Phi(2 * static_cast<Eigen::Index>(k) + 1, 6 + t) = m[t];
    }
  }
  return Phi;
}

/// sigma^2 (P_z M)(P_z M)^T from the dense reference.
Mat5 dense_systematic(const TwoViewRefinement& r, const test::TwoViewScene& s, double sigma_px) {
  const test::DenseTwoView dense = test::dense_two_view(r, s, kSigmaPx);
  const Eigen::MatrixXd& J = dense.J;
  const Eigen::MatrixXd P_z = ((J.transpose() * J).inverse() * J.transpose()).topRows(5);
  const int n = static_cast<int>(s.u_i.size());
  const Eigen::MatrixXd Phi_i = field_basis(s.u_i, s.camera), Phi_j = field_basis(s.u_j, s.camera);
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(4 * n, 24);
  for (int k = 0; k < n; ++k) {
    M.block(4 * k, 0, 2, 12) = Phi_i.middleRows(2 * k, 2) / kSigmaPx;
    M.block(4 * k + 2, 12, 2, 12) = Phi_j.middleRows(2 * k, 2) / kSigmaPx;
  }
  const Eigen::MatrixXd D = P_z * M;
  return sigma_px * sigma_px * D * D.transpose();
}

TwoViewRefinement refine(const test::TwoViewScene& s, double sigma_px, double fraction) {
  TwoViewRefinementOptions o;
  o.pixel_sigma_px = kSigmaPx;
  o.huber_threshold_sigma = 1e9;  // plain least squares: every match kept, the reference's cost
  o.systematic_sigma_px = sigma_px;
  o.systematic_noise_fraction = fraction;
  return refine_two_view(s.u_i, s.u_j, s.camera, core::pose_rotation(s.x_i_j),
                         core::pose_translation(s.x_i_j), o);
}

test::TwoViewScene scene(std::uint32_t seed, int n) {
  std::mt19937 rng(seed);
  return test::make_scene(rng, test::default_x_i_j(), n, 3.5, 0.3, kSigmaPx);
}

TEST(TwoViewSystematic, CovarianceEqualsTheDenseResponseToTheField) {
  const test::TwoViewScene s = scene(31, 60);
  const TwoViewRefinement r = refine(s, 0.2, 0.0);
  ASSERT_TRUE(r.converged) << r.reason;
  ASSERT_EQ(r.used_matches.size(), s.size());
  const Mat5 expected = dense_systematic(r, s, 0.2);
  const double rel = (r.systematic_covariance - expected).norm() / expected.norm();
  std::printf("systematic covariance vs dense: relative difference %.2e\n", rel);
  EXPECT_LT(rel, 1e-4);
  EXPECT_LT((r.covariance - r.information_covariance - r.systematic_covariance).norm(),
            1e-12 * r.covariance.norm());
  // Coherent errors do not average out over the matches: a 0.2 px field outweighs 0.5 px of
  // independent noise on 60 matches along some direction of z.
  const Eigen::GeneralizedSelfAdjointEigenSolver<Mat5> ratio(r.systematic_covariance,
                                                             r.information_covariance);
  std::printf("largest ratio to the information covariance: %.2f\n",
              ratio.eigenvalues().maxCoeff());
  EXPECT_GT(ratio.eigenvalues().maxCoeff(), 1.0);
}

TEST(TwoViewSystematic, NoiseFractionIsTheMeasuredNoiseInPixels) {
  const test::TwoViewScene s = scene(32, 80);
  const TwoViewRefinement by_fraction = refine(s, 0.0, 0.7);
  ASSERT_TRUE(by_fraction.converged) << by_fraction.reason;
  ASSERT_GT(by_fraction.robust_sigma_px, 0.0);
  const TwoViewRefinement by_pixels = refine(s, 0.7 * by_fraction.robust_sigma_px, 0.0);
  EXPECT_EQ(by_fraction.z, by_pixels.z);
  EXPECT_LT((by_fraction.systematic_covariance - by_pixels.systematic_covariance).norm(),
            1e-12 * by_pixels.systematic_covariance.norm());
}

TEST(TwoViewSystematic, ZeroLeavesTheCovarianceAsItWas) {
  const test::TwoViewScene s = scene(33, 40);
  const TwoViewRefinement r = refine(s, 0.0, 0.0);
  ASSERT_TRUE(r.converged) << r.reason;
  EXPECT_EQ(r.systematic_covariance, Mat5::Zero());
  EXPECT_EQ(r.covariance, r.information_covariance);
}

}  // namespace
}  // namespace nav::vision
