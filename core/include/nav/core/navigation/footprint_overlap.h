#pragma once
// Overlap of two camera footprints, and the probability that it reaches a fraction f under a
// Gaussian relative pose: the link hypothesis test of Eustice et al., "Visually Navigating the
// RMS Titanic with SLAM Information Filters" (RSS 2005, sec. IV-A) and Eustice's thesis (MIT/WHOI
// 2005, "link hypothesis"), without Monte Carlo.
//
// Footprint model (nadir-looking pinhole camera over a flat seafloor): camera k sees the
// rectangle [-a_k, a_k] x [-b_k, b_k] of its x (right) / y (down) plane, a_k = altitude_k·cx/fx,
// b_k = altitude_k·cy/fy. In camera j's frame image i's footprint is its rectangle rotated by
// the relative heading ψ (rotation about the optical axis) and centred at the horizontal offset
// t = (t_x, t_y) of camera i. Overlap fraction = area(F_j ∩ F_i) / min(area F_j, area F_i), as
// the simulator's oracle defines it (hil-tests/README.md "Registrations").
//
// Region: for fixed ψ, R_f = {t : overlap(t) >= f}. sqrt(area(F_j ∩ (F_i + t))) is concave in t
// on its support (Brunn-Minkowski) and even (both rectangles are centrally symmetric), so R_f is
// convex and contains t = 0 when not empty, and the overlap falls monotonically along any ray
// from 0. R_f is approximated by the inscribed polygon through its boundary points in
// kRegionDirections directions (bisection along each ray): never larger than R_f.
//
// Probability of a convex polygon under N(μ, C) in 2-D: whiten (u = L⁻¹(t − μ), C = L Lᵀ),
// then exactly P = Σ_edges s_e/(2π) ∫_{α_a}^{α_b} (1 − exp(−h_e²/(2 cos² α))) dα, with h_e the
// distance of the edge's line from the origin, α the angle from its foot and s_e the sign of
// the edge's orientation about the origin (the polar form of the Gaussian integral over the
// triangle origin-edge; signed sums hold whether the origin is inside or not). The α integral
// is by Gauss-Legendre (8 nodes) on pieces of at most 0.2 rad.
//
// Heading: the probability is E_ψ[P(t ∈ R_f(ψ) | ψ)], with t | ψ the conditional Gaussian; the
// expectation by 3-point Gauss-Hermite when σ_ψ > kHeadingQuadratureSigmaRad, else at the mean
// ψ. Approximation error (footprint_overlap_test.cpp, against Monte Carlo of the exact overlap
// under the full 3-D Gaussian): the polygon's inscribed area and the ψ quadrature.

#include <Eigen/Core>
#include <vector>

namespace nav::core {

/// Half extents (a, b) of a footprint, m.
using FootprintHalfExtent = Eigen::Vector2d;

constexpr int kRegionDirections = 32;
constexpr double kHeadingQuadratureSigmaRad = 0.01;

/// area(F_j ∩ F_i) / min(area F_j, area F_i) for image i's footprint at offset `t_j_i_m` and
/// relative heading `heading_j_i_rad` in camera j's frame (file comment). 0 for an empty
/// footprint.
double footprint_overlap_fraction(const FootprintHalfExtent& half_j,
                                  const FootprintHalfExtent& half_i,
                                  const Eigen::Vector2d& t_j_i_m, double heading_j_i_rad);

/// The inscribed polygon of R_f (counter-clockwise vertices, m), empty when even t = 0 overlaps
/// less than `fraction` (in (0, 1]).
std::vector<Eigen::Vector2d> overlap_region(const FootprintHalfExtent& half_j,
                                            const FootprintHalfExtent& half_i,
                                            double heading_j_i_rad, double fraction);

/// P(t ∈ polygon) for t ~ N(mean, covariance) (file comment); `polygon` convex,
/// counter-clockwise. 0 for an empty polygon or a covariance that is not positive definite.
double gaussian_polygon_probability(const std::vector<Eigen::Vector2d>& polygon,
                                    const Eigen::Vector2d& mean, const Eigen::Matrix2d& covariance);

/// P(overlap >= fraction) for the relative camera pose (t_x, t_y, ψ) ~ N(mean, covariance)
/// (3 x 3, in that order; file comment).
double overlap_probability(const FootprintHalfExtent& half_j, const FootprintHalfExtent& half_i,
                           const Eigen::Vector3d& mean, const Eigen::Matrix3d& covariance,
                           double fraction);

}  // namespace nav::core
