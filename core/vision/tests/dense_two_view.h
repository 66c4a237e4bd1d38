#pragma once
// Independent reference for the two-view refinement's covariance tests: the whitened residuals
// as a function of theta = [z; every point in camera i] and their central-difference Jacobian
// at the refinement's solution, built without the solver's analytic Jacobians or its Schur
// complement.

#include <Eigen/Core>
#include <vector>

#include "nav/testing/numeric_jacobian.h"
#include "nav/vision/two_view_refinement.h"
#include "synthetic_two_view.h"

namespace nav::vision::test {

struct DenseTwoView {
  Eigen::MatrixXd J;          ///< d residuals / d theta, 4n x (5 + 3n)
  Eigen::VectorXd residuals;  ///< at the solution
};

inline DenseTwoView dense_two_view(const TwoViewRefinement& r, const TwoViewScene& s,
                                   double pixel_sigma_px) {
  const int n = static_cast<int>(r.points_i.size());
  Eigen::VectorXd theta(5 + 3 * n);
  theta.head<5>() = r.z;
  for (int k = 0; k < n; ++k) theta.segment<3>(5 + 3 * k) = r.points_i[k];
  const auto residuals = [&](const Eigen::VectorXd& v) {
    std::vector<Eigen::Vector3d> X(n);
    for (int k = 0; k < n; ++k) X[k] = v.segment<3>(5 + 3 * k);
    return two_view_residuals(v.head<5>(), X, s.u_i, s.u_j, s.camera, pixel_sigma_px);
  };
  return {nav::testing::numeric_jacobian(residuals, theta, 1e-7), residuals(theta)};
}

}  // namespace nav::vision::test
