#pragma once
// What the robot did since the last state recovery, so that the recovery's warm start can be
// extended once per image instead of per measurement (Eustice et al., RSS 2005 sec. III-A).
// The robot's own predictions (F, Q) and updates (Kalman gain K, I − K H) compose into a linear
// map A with Σ'_ir = Σ_ir Aᵀ for every delayed state i, and a 12 x 12 Kalman filter tracks the
// robot covariance P from the recovered Σ_tt. Both are exact for an exact previous recovery
// except for camera links since (not tracked: P can only be larger than Σ_rr). O(1) per
// measurement. P is also the innovation covariance's prior of the aid sources' NIS.
// The gains K depend on P, so A and P are exact only for the Σ_tt they started from. With a
// recovery thread the filter restarts from its own (stale) iterate and later receives the job's
// exact Σ_tt of the same snapshot: with `record_steps` the tracker keeps every step since the
// restart (about 260 per image on the default dive) and replay_from() recomputes A and P from
// that Σ_tt, so the job's iterate is extended exactly instead of to first order.

#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/core/models/measurement.h"

namespace nav::core {

/// One robot step: a prediction (meas_dim 0: a = F, b = Q) or an update (a = H in its first
/// meas_dim rows, b = R in its top-left meas_dim x meas_dim corner).
struct RobotStep {
  Mat12 a = Mat12::Zero();
  Mat12 b = Mat12::Zero();
  int meas_dim = 0;
};

struct WarmStartTracker {
  Mat12 A = Mat12::Identity();  ///< composed F and I − K H since the last recovery
  Mat12 P = Mat12::Zero();      ///< robot covariance tracked from sigma_tt
  Mat12 sigma_tt = Mat12::Zero();  ///< the last recovery's Σ_rr
  bool predicted = false;       ///< a prediction since the last recovery
  int kept = -1;                ///< block kept by such a prediction, or -1
  bool record_steps = false;    ///< keep `steps` for replay_from (the recovery thread)
  std::vector<RobotStep> steps;  ///< the steps since the last restart (record_steps)

  /// Starts from a recovered (or prior) robot covariance.
  void restart(const Mat12& sigma) {
    sigma_tt = sigma;
    P = sigma;
    steps.clear();
  }
  /// Σ_tt = sigma, and A and P as if the last restart had started from it: the recorded steps
  /// (record_steps must be set) applied again; A and P are kept if that P is not SPD (a
  /// truncated recovery's Σ_tt may be indefinite). Keeps the steps.
  void replay_from(const Mat12& sigma);
  /// A prediction x' = f(x), F, Q (keeping block `kept_block` >= 0, or -1).
  void predicted_with(const Mat12& F, const Mat12& Q, int kept_block);
  /// A robot update with Jacobian H and noise R (Joseph form on P); skipped if H P Hᵀ + R is
  /// not positive definite.
  void updated_with(const MeasJac& H, const MeasCov& R);
  /// After the warm start was extended: A = I, nothing since.
  void extended() {
    A.setIdentity();
    predicted = false;
    kept = -1;
  }
};

}  // namespace nav::core
