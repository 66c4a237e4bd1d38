// The robot's predictions and updates since the last recovery (navigation/warm_start_tracker.h).
#include "nav/core/navigation/warm_start_tracker.h"

#include <Eigen/Cholesky>

namespace nav::core {

void WarmStartTracker::predicted_with(const Mat12& F, const Mat12& Q, int kept_block) {
  A = F * A;
  P = F * P * F.transpose() + Q;
  predicted = true;
  if (kept_block >= 0) kept = kept_block;
}

void WarmStartTracker::updated_with(const MeasJac& H, const MeasCov& R) {
  const Eigen::MatrixXd PHt = P * H.transpose();
  const Eigen::LLT<Eigen::MatrixXd> llt(H * PHt + R);
  if (llt.info() != Eigen::Success) return;
  const Eigen::MatrixXd K = llt.solve(PHt.transpose()).transpose();
  const Mat12 IKH = Mat12::Identity() - K * H;
  A = IKH * A;
  P = IKH * P * IKH.transpose() + K * R * K.transpose();
}

}  // namespace nav::core
