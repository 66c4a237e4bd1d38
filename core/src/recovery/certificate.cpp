// Small dense helpers of the covariance certificate (recovery/certificate.h).
#include "nav/core/recovery/certificate.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>

namespace nav::core {

double kappa_squared_split(double a, double b) {
  const double root = std::sqrt(std::max(0.0, a)) + std::sqrt(std::max(0.0, b));
  return root * root;
}

double lambda_max_symmetric(const Eigen::MatrixXd& m) {
  const Eigen::MatrixXd s = 0.5 * (m + m.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(s, Eigen::EigenvaluesOnly);
  return solver.eigenvalues().maxCoeff();
}

double lambda_max_scaled(const Eigen::MatrixXd& G, const Eigen::MatrixXd& W) {
  // λmax(W^-½ G W^-½) = largest generalised eigenvalue of G v = λ W v (W SPD).
  const Eigen::MatrixXd g = 0.5 * (G + G.transpose()), w = 0.5 * (W + W.transpose());
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> solver(g, w, Eigen::EigenvaluesOnly);
  if (solver.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  return std::max(0.0, solver.eigenvalues().maxCoeff());
}

Eigen::MatrixXd weighted_block_gram(const Eigen::Ref<const Eigen::MatrixXd>& R, int first, int last,
                                    const Eigen::MatrixXd& W,
                                    const std::function<const Eigen::MatrixXd&(int)>& bound) {
  const auto d = W.rows();
  Eigen::MatrixXd sum = R.topRows(d).transpose() * W * R.topRows(d);
  for (int j = std::max(first, 1); j < last; ++j) {
    const auto R_j = R.middleRows(j * d, d);
    sum.noalias() += R_j.transpose() * bound(j) * R_j;
  }
  return sum;
}

}  // namespace nav::core
