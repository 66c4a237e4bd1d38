#pragma once
// One numerical-differentiation helper for every analytic Jacobian in navd (docs/architecture.md
// "Conventions", as gtsam/base/numericalDerivative.h). Central differences, O(h^2) truncation
// error.

#include <Eigen/Core>
#include <functional>

namespace nav::testing {

/// Central-difference Jacobian of f at x. `minus(a, b)` is the local difference a - b of the
/// output space (e.g. wrapping angle components); by default the plain vector difference.
/// Step h is relative: h_k = h * max(1, |x_k|).
inline Eigen::MatrixXd numeric_jacobian(
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& x,
    double h = 1e-6,
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&, const Eigen::VectorXd&)>& minus =
        nullptr) {
  const Eigen::VectorXd f0 = f(x);
  Eigen::MatrixXd J(f0.size(), x.size());
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    const double step = h * std::max(1.0, std::abs(x[k]));
    Eigen::VectorXd xp = x, xm = x;
    xp[k] += step;
    xm[k] -= step;
    const Eigen::VectorXd fp = f(xp), fm = f(xm);
    J.col(k) = (minus ? minus(fp, fm) : Eigen::VectorXd(fp - fm)) / (2.0 * step);
  }
  return J;
}

/// Largest absolute difference, for messages: "max |A - B| = ..." .
inline double max_abs_diff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

}  // namespace nav::testing
