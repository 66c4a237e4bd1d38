// Consistency metrics (recovery/consistency.h; Eustice et al., RSS 2005, Sec. IV, Fig. 3).

#include "nav/core/recovery/consistency.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

#include "nav/core/geometry/pose.h"

namespace nav::core {

bool is_conservative(const Eigen::MatrixXd& bound, const Eigen::MatrixXd& exact, double tol,
                     double* min_eig) {
  if (bound.rows() != bound.cols() || bound.rows() != exact.rows() ||
      exact.rows() != exact.cols()) {
    throw std::invalid_argument("is_conservative: bound is " + std::to_string(bound.rows()) + "x" +
                                std::to_string(bound.cols()) + ", exact is " +
                                std::to_string(exact.rows()) + "x" + std::to_string(exact.cols()));
  }
  const Eigen::MatrixXd diff = 0.5 * (bound - exact + (bound - exact).transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> exact_eig(exact, Eigen::EigenvaluesOnly);
  const double norm =
      std::max(exact_eig.eigenvalues().cwiseAbs().maxCoeff(), std::numeric_limits<double>::min());
  const double shift = tol * norm;
  if (min_eig != nullptr) {
    *min_eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(diff, Eigen::EigenvaluesOnly)
                   .eigenvalues()
                   .minCoeff();
  }
  const Eigen::MatrixXd shifted =
      diff + shift * Eigen::MatrixXd::Identity(diff.rows(), diff.cols());
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(shifted);
  if (ldlt.info() != Eigen::Success) return false;
  return (ldlt.vectorD().array() >= 0.0).all();
}

Mat6 relative_pose_covariance(const Mat12& joint, const Vec6& x_r, const Vec6& x_i) {
  Mat6x12 J;
  tail_to_tail(x_r, x_i, &J);
  Mat6 cov = J * joint * J.transpose();
  return 0.5 * (cov + cov.transpose());
}

Mat12 pose_joint(const Eigen::MatrixXd& joint) {
  const Eigen::Index d = joint.rows() / 2;
  if (joint.rows() != joint.cols() || joint.rows() % 2 != 0 || d < 6) {
    throw std::invalid_argument("pose_joint: the joint must be 2d x 2d with d >= 6, is " +
                                std::to_string(joint.rows()) + "x" +
                                std::to_string(joint.cols()));
  }
  Mat12 p;
  p << joint.block<6, 6>(0, 0), joint.block<6, 6>(0, d), joint.block<6, 6>(d, 0),
      joint.block<6, 6>(d, d);
  return p;
}

namespace {
double logdet_spd(const Eigen::Ref<const Eigen::MatrixXd>& m, const char* name) {
  if (m.rows() != m.cols() || m.rows() == 0) {
    throw std::invalid_argument(std::string("logdet_ratio: ") + name + " is " +
                                std::to_string(m.rows()) + "x" + std::to_string(m.cols()) +
                                ", not square and non-empty");
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(m);
  if (llt.info() != Eigen::Success) {
    throw std::invalid_argument(std::string("logdet_ratio: ") + name +
                                " is not symmetric positive definite");
  }
  return 2.0 * llt.matrixLLT().diagonal().array().log().sum();
}
}  // namespace

double logdet_ratio(const Eigen::Ref<const Eigen::MatrixXd>& ours,
                    const Eigen::Ref<const Eigen::MatrixXd>& exact) {
  if (ours.rows() != exact.rows() || ours.cols() != exact.cols()) {
    throw std::invalid_argument("logdet_ratio: sizes differ");
  }
  return logdet_spd(ours, "ours") - logdet_spd(exact, "exact");
}

SummaryStats summarize(std::vector<double> values) {
  if (values.empty()) throw std::invalid_argument("summarize: no values");
  std::sort(values.begin(), values.end());
  SummaryStats s;
  s.count = values.size();
  s.min = values.front();
  s.max = values.back();
  const size_t mid = values.size() / 2;
  s.median = values.size() % 2 == 1 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
  return s;
}

}  // namespace nav::core
