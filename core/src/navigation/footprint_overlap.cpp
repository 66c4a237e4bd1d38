// Footprint overlap and its probability (navigation/footprint_overlap.h).
#include "nav/core/navigation/footprint_overlap.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>

namespace nav::core {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kBisections = 14;          // boundary to 2^-14 of the largest reach
constexpr double kMaxPieceRad = 0.2;     // Gauss-Legendre piece width in α
constexpr int kMaxVertices = 12;         // a quadrilateral clipped by 4 half-planes: <= 8

/// A small convex polygon without heap allocation (the per-candidate inner loop).
struct SmallPolygon {
  std::array<Eigen::Vector2d, kMaxVertices> v;
  int n = 0;
};

/// Sutherland-Hodgman: keeps the part of `in` with sign·x[axis] <= limit.
SmallPolygon clip(const SmallPolygon& in, int axis, double sign, double limit) {
  SmallPolygon out;
  for (int k = 0; k < in.n; ++k) {
    const Eigen::Vector2d& p = in.v[static_cast<std::size_t>(k)];
    const Eigen::Vector2d& q = in.v[static_cast<std::size_t>((k + 1) % in.n)];
    const double dp = sign * p[axis] - limit, dq = sign * q[axis] - limit;
    if (dp <= 0.0) out.v[static_cast<std::size_t>(out.n++)] = p;
    if ((dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0)) {
      out.v[static_cast<std::size_t>(out.n++)] = p + (dp / (dp - dq)) * (q - p);
    }
  }
  return out;
}

double area(const SmallPolygon& poly) {
  double twice = 0.0;
  for (int k = 0; k < poly.n; ++k) {
    const Eigen::Vector2d& p = poly.v[static_cast<std::size_t>(k)];
    const Eigen::Vector2d& q = poly.v[static_cast<std::size_t>((k + 1) % poly.n)];
    twice += p.x() * q.y() - p.y() * q.x();
  }
  return 0.5 * std::abs(twice);
}

double cross(const Eigen::Vector2d& p, const Eigen::Vector2d& q) {
  return p.x() * q.y() - p.y() * q.x();
}

/// (1/2π) ∫_{α_a}^{α_b} (1 − exp(−h²/(2 cos² α))) dα, α_a <= α_b in (−π/2, π/2).
double edge_integral(double h, double alpha_a, double alpha_b) {
  static constexpr std::array<double, 4> kNode = {0.1834346424956498, 0.5255324099163290,
                                                  0.7966664774136267, 0.9602898564975363};
  static constexpr std::array<double, 4> kWeight = {0.3626837833783620, 0.3137066458778873,
                                                    0.2223810344533745, 0.1012285362903763};
  const int pieces = std::max(1, static_cast<int>(std::ceil((alpha_b - alpha_a) / kMaxPieceRad)));
  const double width = (alpha_b - alpha_a) / pieces;
  double sum = 0.0;
  for (int k = 0; k < pieces; ++k) {
    const double mid = alpha_a + (k + 0.5) * width, half = 0.5 * width;
    for (std::size_t n = 0; n < kNode.size(); ++n) {
      for (const double s : {-1.0, 1.0}) {
        const double c = std::cos(mid + s * half * kNode[n]);
        sum += kWeight[n] * half * -std::expm1(-h * h / (2.0 * c * c));
      }
    }
  }
  return sum / (2.0 * kPi);
}

}  // namespace

double footprint_overlap_fraction(const FootprintHalfExtent& half_j,
                                  const FootprintHalfExtent& half_i,
                                  const Eigen::Vector2d& t_j_i_m, double heading_j_i_rad) {
  const double area_j = 4.0 * half_j.x() * half_j.y(), area_i = 4.0 * half_i.x() * half_i.y();
  if (!(area_j > 0.0 && area_i > 0.0)) return 0.0;
  const double c = std::cos(heading_j_i_rad), s = std::sin(heading_j_i_rad);
  SmallPolygon poly;
  const double corner[4][2] = {{1, 1}, {-1, 1}, {-1, -1}, {1, -1}};  // counter-clockwise
  for (const auto& k : corner) {
    const double x = k[0] * half_i.x(), y = k[1] * half_i.y();
    poly.v[static_cast<std::size_t>(poly.n++)] = t_j_i_m + Eigen::Vector2d(c * x - s * y, s * x + c * y);
  }
  for (int axis = 0; axis < 2 && poly.n > 0; ++axis) {
    poly = clip(poly, axis, 1.0, half_j[axis]);
    if (poly.n > 0) poly = clip(poly, axis, -1.0, half_j[axis]);
  }
  return poly.n < 3 ? 0.0 : area(poly) / std::min(area_j, area_i);
}

std::vector<Eigen::Vector2d> overlap_region(const FootprintHalfExtent& half_j,
                                            const FootprintHalfExtent& half_i,
                                            double heading_j_i_rad, double fraction) {
  std::vector<Eigen::Vector2d> polygon;
  if (footprint_overlap_fraction(half_j, half_i, Eigen::Vector2d::Zero(), heading_j_i_rad) <
      fraction) {
    return polygon;
  }
  const double reach_m = half_j.norm() + half_i.norm();  // beyond it the footprints are apart
  // R_f is centrally symmetric (overlap(t) = overlap(-t), file comment): the boundary is
  // bisected in the first half of the directions and mirrored into the second.
  static_assert(kRegionDirections % 2 == 0, "mirrored directions need an even count");
  constexpr int kHalf = kRegionDirections / 2;
  polygon.resize(kRegionDirections);
  for (int k = 0; k < kHalf; ++k) {
    const double theta = 2.0 * kPi * k / kRegionDirections;
    const Eigen::Vector2d u(std::cos(theta), std::sin(theta));
    double inside = 0.0, outside = reach_m;
    for (int it = 0; it < kBisections; ++it) {
      const double mid = 0.5 * (inside + outside);
      const bool in =
          footprint_overlap_fraction(half_j, half_i, mid * u, heading_j_i_rad) >= fraction;
      (in ? inside : outside) = mid;
    }
    polygon[k] = inside * u;
    polygon[k + kHalf] = -inside * u;
  }
  return polygon;
}

double gaussian_polygon_probability(const std::vector<Eigen::Vector2d>& polygon,
                                    const Eigen::Vector2d& mean, const Eigen::Matrix2d& covariance) {
  if (polygon.size() < 3) return 0.0;
  const Eigen::LLT<Eigen::Matrix2d> llt(covariance);
  if (llt.info() != Eigen::Success) return 0.0;
  const Eigen::Matrix2d L = llt.matrixL();
  std::vector<Eigen::Vector2d> u(polygon.size());
  for (std::size_t k = 0; k < polygon.size(); ++k) {
    u[k] = L.triangularView<Eigen::Lower>().solve(polygon[k] - mean);  // det L > 0: still CCW
  }
  double p = 0.0;
  for (std::size_t k = 0; k < u.size(); ++k) {
    const Eigen::Vector2d& a = u[k];
    const Eigen::Vector2d& b = u[(k + 1) % u.size()];
    const Eigen::Vector2d d = b - a;
    const double length = d.norm();
    const double cr = cross(a, b);
    if (!(length > 0.0) || cr == 0.0) continue;  // origin on the edge's line: contributes 0
    const Eigen::Vector2d dir = d / length;
    const double h = std::abs(cr) / length;
    const double alpha_a = std::atan2(a.dot(dir), h), alpha_b = std::atan2(b.dot(dir), h);
    p += (cr > 0.0 ? 1.0 : -1.0) * edge_integral(h, alpha_a, alpha_b);
  }
  return std::clamp(p, 0.0, 1.0);
}

double overlap_probability(const FootprintHalfExtent& half_j, const FootprintHalfExtent& half_i,
                           const Eigen::Vector3d& mean, const Eigen::Matrix3d& covariance,
                           double fraction) {
  const Eigen::Vector2d mean_t = mean.head<2>();
  const Eigen::Matrix2d cov_t = covariance.topLeftCorner<2, 2>();
  const double var_psi = covariance(2, 2);
  if (!(var_psi > kHeadingQuadratureSigmaRad * kHeadingQuadratureSigmaRad)) {
    return gaussian_polygon_probability(overlap_region(half_j, half_i, mean(2), fraction), mean_t,
                                        cov_t);
  }
  // 3-point Gauss-Hermite in ψ of the conditional Gaussian t | ψ.
  const double sigma_psi = std::sqrt(var_psi);
  const Eigen::Vector2d gain = covariance.block<2, 1>(0, 2) / var_psi;
  const Eigen::Matrix2d cov_given =
      cov_t - gain * covariance.block<1, 2>(2, 0);
  if (Eigen::LLT<Eigen::Matrix2d>(cov_given).info() != Eigen::Success) {
    return gaussian_polygon_probability(overlap_region(half_j, half_i, mean(2), fraction), mean_t,
                                        cov_t);
  }
  const double root3 = std::sqrt(3.0);
  double p = 0.0;
  for (const auto& [z, w] : {std::pair{-root3, 1.0 / 6.0}, std::pair{0.0, 2.0 / 3.0},
                             std::pair{root3, 1.0 / 6.0}}) {
    const double dpsi = z * sigma_psi;
    p += w * gaussian_polygon_probability(overlap_region(half_j, half_i, mean(2) + dpsi, fraction),
                                          mean_t + gain * dpsi, cov_given);
  }
  return std::clamp(p, 0.0, 1.0);
}

}  // namespace nav::core
