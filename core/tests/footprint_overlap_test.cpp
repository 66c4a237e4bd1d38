// Footprint overlap and its probability (navigation/footprint_overlap.h) against independent
// references: closed-form overlaps of rectangles, the separable Gaussian probability of a box
// (erf), and Monte Carlo of the exact overlap under the full (t_x, t_y, ψ) Gaussian.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdio>
#include <random>

#include "nav/core/navigation/footprint_overlap.h"
#include "nav/core/navigation/link_proposer.h"

namespace nav::core {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(FootprintOverlap, MatchesClosedFormForAlignedRectangles) {
  const FootprintHalfExtent half(2.0, 1.5);
  EXPECT_NEAR(footprint_overlap_fraction(half, half, {0.0, 0.0}, 0.0), 1.0, 1e-12);
  // Offset (dx, dy): (1 − |dx|/2a)(1 − |dy|/2b).
  EXPECT_NEAR(footprint_overlap_fraction(half, half, {1.0, -0.6}, 0.0),
              (1.0 - 1.0 / 4.0) * (1.0 - 0.6 / 3.0), 1e-12);
  // A rectangle turned by π is the same rectangle (a reciprocal survey line).
  EXPECT_NEAR(footprint_overlap_fraction(half, half, {1.0, -0.6}, kPi),
              (1.0 - 1.0 / 4.0) * (1.0 - 0.6 / 3.0), 1e-12);
  EXPECT_EQ(footprint_overlap_fraction(half, half, {4.1, 0.0}, 0.0), 0.0);
  // Turned by 90°: the 3 x 4 rectangle inside the 4 x 3 one covers 3 x 3 of its 12 m².
  EXPECT_NEAR(footprint_overlap_fraction(half, half, {0.0, 0.0}, kPi / 2), 9.0 / 12.0, 1e-12);
  // Different sizes: the smaller footprint (inside the larger) overlaps fully.
  EXPECT_NEAR(footprint_overlap_fraction(half, 0.5 * half, {0.3, 0.3}, 0.3), 1.0, 1e-12);
}

/// Every vertex of overlap_region (bisected or mirrored through the origin) lies on the boundary
/// of R_f from inside.
void expect_vertices_on_the_boundary(const FootprintHalfExtent& half_j,
                                     const FootprintHalfExtent& half_i, double heading_rad,
                                     double fraction) {
  const auto region = overlap_region(half_j, half_i, heading_rad, fraction);
  ASSERT_EQ(region.size(), static_cast<std::size_t>(kRegionDirections));
  for (const Eigen::Vector2d& v : region) {
    const double f = footprint_overlap_fraction(half_j, half_i, v, heading_rad);
    EXPECT_GE(f, fraction) << v.transpose();
    EXPECT_LT(f, fraction + 1e-3) << v.transpose();
  }
}

TEST(FootprintOverlap, RegionIsInscribedAndTight) {
  const FootprintHalfExtent half(2.0, 1.5);
  expect_vertices_on_the_boundary(half, half, 0.0, 0.5);
  // On the x axis the boundary is at 1 − dx/4 = 0.5: dx = 2.
  EXPECT_NEAR(overlap_region(half, half, 0.0, 0.5)[0].x(), 2.0, 1e-3);
  EXPECT_TRUE(overlap_region(half, half, kPi / 2, 0.8).empty());  // even t = 0 gives 0.75
  // Unequal footprints at a relative heading.
  expect_vertices_on_the_boundary(half, FootprintHalfExtent(1.2, 0.8), 0.7, 0.3);
}

TEST(FootprintOverlap, GaussianBoxProbabilityIsTheErfProduct) {
  const std::vector<Eigen::Vector2d> box = {{1, -1}, {1, 1}, {-1, 1}, {-1, -1}};
  auto phi = [](double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); };
  const Eigen::Vector2d mean(0.3, -0.2);
  const double sx = 0.7, sy = 1.3;
  const Eigen::Matrix2d cov = Eigen::Vector2d(sx * sx, sy * sy).asDiagonal();
  const double expected = (phi((1 - mean.x()) / sx) - phi((-1 - mean.x()) / sx)) *
                          (phi((1 - mean.y()) / sy) - phi((-1 - mean.y()) / sy));
  EXPECT_NEAR(gaussian_polygon_probability(box, mean, cov), expected, 2e-4);
  // The origin far outside the box: the signed edge sum must cancel to the small tail.
  const Eigen::Vector2d far(4.0, 0.0);
  const double tail = (phi((1 - far.x()) / sx) - phi((-1 - far.x()) / sx)) *
                      (phi(1 / sy) - phi(-1 / sy));
  EXPECT_NEAR(gaussian_polygon_probability(box, far, cov), tail, 2e-4);
}

/// Monte Carlo reference: fraction of (t_x, t_y, ψ) samples whose exact overlap >= f.
double monte_carlo(const FootprintHalfExtent& hj, const FootprintHalfExtent& hi,
                   const Eigen::Vector3d& mean, const Eigen::Matrix3d& cov, double f, int n) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  const Eigen::Matrix3d L = cov.llt().matrixL();
  int hits = 0;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d x = mean + L * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    hits += footprint_overlap_fraction(hj, hi, x.head<2>(), x(2)) >= f ? 1 : 0;
  }
  return static_cast<double>(hits) / n;
}

TEST(FootprintOverlap, ProbabilityMatchesMonteCarlo) {
  const FootprintHalfExtent hj(2.4, 1.8), hi(2.0, 1.5);  // two altitudes
  struct Case {
    Eigen::Vector3d mean;
    Eigen::Vector3d sigma;  // t_x m, t_y m, ψ rad
    double rho_xy, rho_x_psi;
  };
  const Case cases[] = {
      {{0.5, 0.2, 0.1}, {1.2, 0.9, 0.005}, 0.0, 0.0},      // mean inside, wide spread
      {{2.6, 0.4, 0.0}, {0.6, 0.4, 0.005}, 0.5, 0.0},      // near the boundary, correlated
      {{5.0, -1.0, 3.0}, {1.0, 0.8, 0.005}, -0.3, 0.0},    // mostly outside, reciprocal line
      {{1.5, 1.0, 0.4}, {1.2, 0.9, 0.15}, 0.2, 0.6},       // uncertain heading (Gauss-Hermite)
  };
  for (const Case& c : cases) {
    Eigen::Matrix3d corr = Eigen::Matrix3d::Identity();
    corr(0, 1) = corr(1, 0) = c.rho_xy;
    corr(0, 2) = corr(2, 0) = c.rho_x_psi;
    const Eigen::Matrix3d cov = c.sigma.asDiagonal() * corr * c.sigma.asDiagonal();
    const double p = overlap_probability(hj, hi, c.mean, cov, 0.2);
    const double mc = monte_carlo(hj, hi, c.mean, cov, 0.2, 40000);  // sd <= 0.0025
    std::printf("overlap probability %.4f, Monte Carlo %.4f\n", p, mc);
    EXPECT_NEAR(p, mc, 0.015) << "mean " << c.mean.transpose();
  }
}

LinkHypothesis hypothesis(int state, double probability, double overlap) {
  LinkHypothesis h;
  h.joint.state = state;
  h.overlap_probability = probability;
  h.overlap_at_mean = overlap;
  return h;
}

TEST(LinkProposer, RanksByProbabilityThenOverlapAndCaps) {
  LinkProposerOptions o;
  o.max_per_image = 3;
  const LinkProposer proposer(o, {0.5, 0.4}, Vec6::Zero());
  std::vector<LinkHypothesis> h = {hypothesis(1, 0.2, 0.9), hypothesis(2, 0.99, 0.3),
                                   hypothesis(3, 0.99, 0.6), hypothesis(4, 0.5, 0.5),
                                   hypothesis(5, 0.1, 0.9)};
  proposer.rank_and_cap(h);
  ASSERT_EQ(h.size(), 3u);
  EXPECT_EQ(h[0].joint.state, 3);  // equal probability: larger overlap at the mean first
  EXPECT_EQ(h[1].joint.state, 2);
  EXPECT_EQ(h[2].joint.state, 4);
  EXPECT_THROW(LinkProposer(LinkProposerOptions{0.0, 0.2, 15}, {0.5, 0.4}, Vec6::Zero()),
               std::invalid_argument);
  EXPECT_THROW(LinkProposer(LinkProposerOptions{0.05, 0.2, 0}, {0.5, 0.4}, Vec6::Zero()),
               std::invalid_argument);
}

}  // namespace
}  // namespace nav::core
