// The robot's predictions and updates since the last recovery (navigation/warm_start_tracker.h).
#include "nav/core/navigation/warm_start_tracker.h"

#include <Eigen/Cholesky>

namespace nav::core {

namespace {

void predict(const Mat12& F, const Mat12& Q, Mat12& A, Mat12& P) {
  A = F * A;
  P = F * P * F.transpose() + Q;
}

/// Joseph-form update of P, I − K H into A; false (nothing changed) if H P Hᵀ + R is not SPD.
template <class H_t, class R_t>
bool update(const H_t& H, const R_t& R, Mat12& A, Mat12& P) {
  const Eigen::MatrixXd PHt = P * H.transpose();
  const Eigen::LLT<Eigen::MatrixXd> llt(H * PHt + R);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::MatrixXd K = llt.solve(PHt.transpose()).transpose();
  const Mat12 IKH = Mat12::Identity() - K * H;
  A = IKH * A;
  P = IKH * P * IKH.transpose() + K * R * K.transpose();
  return true;
}

}  // namespace

void WarmStartTracker::predicted_with(const Mat12& F, const Mat12& Q, int kept_block) {
  predict(F, Q, A, P);
  predicted = true;
  if (kept_block >= 0) kept = kept_block;
  if (record_steps) steps.push_back(RobotStep{F, Q, 0});
}

void WarmStartTracker::updated_with(const MeasJac& H, const MeasCov& R) {
  if (!update(H, R, A, P) || !record_steps) return;
  RobotStep step;
  step.meas_dim = static_cast<int>(H.rows());
  step.a.topRows(H.rows()) = H;
  step.b.topLeftCorner(R.rows(), R.cols()) = R;
  steps.push_back(step);
}

void WarmStartTracker::replay_from(const Mat12& sigma) {
  Mat12 A_new = Mat12::Identity(), P_new = sigma;
  for (const RobotStep& s : steps) {
    const int m = s.meas_dim;
    if (m == 0) {
      predict(s.a, s.b, A_new, P_new);
    } else {
      (void)update(s.a.topRows(m), s.b.topLeftCorner(m, m), A_new, P_new);
    }
  }
  sigma_tt = sigma;
  if (Eigen::LLT<Mat12>(P_new).info() != Eigen::Success) return;
  A = A_new;
  P = P_new;
}

}  // namespace nav::core
