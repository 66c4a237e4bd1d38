// The 5-dof gate of a registered pair and its iterated linearisation point
// (navigation/link_gate.h, navigation/link_linearisation.h).
#include "nav/core/navigation/link_gate.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "nav/core/geometry/rotation.h"
#include "nav/core/navigation/chi_square.h"

namespace nav::core {
namespace {

constexpr int kD = 12;  // block dimension

}  // namespace

/// The certified joint of the proposal (bounds.h), as it is (link_gate.h).
Eigen::MatrixXd LinkGate::gate_joint(const LinkProposal& p) { return p.joint; }

bool LinkGate::mahalanobis_sq(const Eigen::Matrix<double, 5, 5>& S, const MeasVec& nu,
                              double* d2) {
  // LLT fails on a non-positive pivot: an indefinite S cannot produce a (negative) d² that
  // passes, as an LDLT without a sign check of D could.
  const Eigen::LLT<Eigen::Matrix<double, 5, 5>> llt(0.5 * (S + S.transpose()));
  if (llt.info() != Eigen::Success || !S.allFinite()) return false;
  *d2 = llt.matrixL().solve(nu).squaredNorm();
  return std::isfinite(*d2);
}

/// The 5-dof gate at the means x0 = [x_j; x_i] with the joint covariance: fills the link's
/// innovation and Mahalanobis distance; true when it passes (link_gate.h).
bool LinkGate::pass(const CameraRelativePoseModel& camera, const LinkPair& x0,
                    const Eigen::MatrixXd& joint_cov, const RegistrationResult& reg,
                    LinkRecord& link) const {
  const auto x_r = x0.head<kD>(), x_i = x0.tail<kD>();
  if (camera.baseline_is_degenerate(x_i, x_r)) return false;
  try {
    MeasJac H_i, H_r;
    MeasVec nu = reg.z - camera.predict(x_i, x_r, &H_i, &H_r);
    for (int row = 0; row < 5; ++row) nu(row) = wrap_angle(nu(row));
    Eigen::Matrix<double, 5, 2 * kD> H;
    H << H_r, H_i;
    const Eigen::Matrix<double, 5, 5> S = H * joint_cov * H.transpose() + reg.covariance;
    link.innovation = nu;
    double d2 = std::numeric_limits<double>::infinity();
    const bool positive_definite = mahalanobis_sq(S, nu, &d2);
    link.mahalanobis_sq = d2;
    return positive_definite && d2 <= gate_chi2_;
  } catch (const std::exception& e) {
    if (warn_) {
      warn_("NavFilter: camera model for frames " + std::to_string(link.frame_i) + "-" +
            std::to_string(link.frame_j) + ": " + e.what());
    }
    return false;
  }
}

/// The accepted link's linearisation at the robot's iterated point (link_linearisation.h;
/// link_gate.h), or at the means where the iteration fails.
LinkLinearisation LinkGate::linearise(const CameraRelativePoseModel& camera, const LinkPair& x0,
                                      const Eigen::MatrixXd& joint_cov,
                                      const RegistrationResult& reg, const LinkRecord& link) const {
  LinkLinearisation lin;
  try {
    // Only the robot moves: J's robot block is the recovered Σ_rr, while state i's is its
    // conservative bound (loose by orders of magnitude), which would drag x_i to the link.
    Eigen::MatrixXd robot_only = Eigen::MatrixXd::Zero(2 * kD, 2 * kD);
    robot_only.topLeftCorner(kD, kD) = joint_cov.topLeftCorner(kD, kD);
    lin = iterated_link_point(camera, x0, robot_only, reg.z, reg.covariance);
  } catch (const std::exception& e) {  // a degenerate iterate: the mean is the point
    if (warn_) {
      warn_("NavFilter: camera link " + std::to_string(link.frame_i) + "-" +
            std::to_string(link.frame_j) + " not iterated: " + e.what());
    }
    lin = LinkLinearisation{};
    lin.x = x0;
    lin.h = camera.predict(x0.tail<kD>(), x0.head<kD>(), &lin.H_i, &lin.H_r);
  }
  return lin;
}

/// a - b with the attitude components wrapped to (-π, π].
LinkPair wrapped_difference(const LinkPair& a, const LinkPair& b) {
  LinkPair d = a - b;
  for (int k = 3; k < 6; ++k) {
    d[k] = wrap_angle(d[k]);
    d[kD + k] = wrap_angle(d[kD + k]);
  }
  return d;
}

LinkLinearisation iterated_link_point(const CameraRelativePoseModel& camera, const LinkPair& x0,
                                      const Eigen::MatrixXd& joint, const MeasVec& z,
                                      const MeasCov& R) {
  constexpr int kMaxIterations = 10;
  constexpr double kConverged = 1e-9;  // step norm (m, rad)
  LinkLinearisation l;
  l.x = x0;
  for (;;) {
    l.h = camera.predict(l.x.tail<kD>(), l.x.head<kD>(), &l.H_i, &l.H_r);
    if (l.iterations == kMaxIterations) return l;
    Eigen::Matrix<double, 5, 2 * kD> H;
    H << l.H_r, l.H_i;
    Eigen::Matrix<double, 2 * kD, 1> dx = x0 - l.x;
    for (int k = 3; k < 6; ++k) {  // Euler angles of both blocks along the shorter arc
      dx[k] = wrap_angle(dx[k]);
      dx[kD + k] = wrap_angle(dx[kD + k]);
    }
    MeasVec r = z - l.h;
    wrap_angle_rows(camera, r);
    const Eigen::Matrix<double, 5, 1> nu = r - H * dx;
    const Eigen::Matrix<double, 5, 5> S = H * joint * H.transpose() + R;
    const Eigen::Matrix<double, 2 * kD, 1> next =
        x0 + joint * H.transpose() * Eigen::LDLT<Eigen::Matrix<double, 5, 5>>(S).solve(nu);
    if (!next.allFinite()) return l;
    const double step = (next - l.x).norm();
    l.x = next;
    ++l.iterations;
    if (step < kConverged) {
      l.h = camera.predict(l.x.tail<kD>(), l.x.head<kD>(), &l.H_i, &l.H_r);
      return l;
    }
  }
}

}  // namespace nav::core
