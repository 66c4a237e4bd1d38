#pragma once
// Uncertainty ellipses and ellipsoids of Gaussian position covariances for display.
// For a 2x2 covariance P = R diag(l1, l2) R^T (l1 >= l2, eigen-decomposition), the k-sigma
// ellipse has semi-axes k*sqrt(l1), k*sqrt(l2) and its major axis at angle atan2(R(1,0), R(0,0))
// from x (north) towards y (east). Closed form for the symmetric 2x2 case.
#include <array>

namespace nav::daemon::topside {

struct Ellipse2 {
  double semi_major_m = 0.0;
  double semi_minor_m = 0.0;
  double angle_rad = 0.0;  ///< of the major axis, from +x (north) towards +y (east), in (-pi/2, pi/2]
};

/// The k_sigma ellipse of the covariance [[pxx, pxy], [pxy, pyy]] (m^2). Negative eigenvalues
/// from round-off are clamped to zero.
Ellipse2 covariance_ellipse(double pxx_m2, double pxy_m2, double pyy_m2, double k_sigma);

/// A k_sigma ellipsoid of a 3x3 position covariance (row-major): full axis lengths (2 k sqrt(l))
/// in the order of the principal axes, and the rotation from the principal frame to the
/// covariance's frame as a unit quaternion (x, y, z, w).
struct Ellipsoid3 {
  std::array<double, 3> size_m{};
  std::array<double, 4> q_xyzw{0.0, 0.0, 0.0, 1.0};
};
Ellipsoid3 covariance_ellipsoid(const std::array<double, 9>& p_m2, double k_sigma);

/// Row-major 3x3 position block of a 6x6 row-major pose covariance.
std::array<double, 9> position_block(const double* cov6x6);

}  // namespace nav::daemon::topside
