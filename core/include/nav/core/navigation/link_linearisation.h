#pragma once
// Where NavFilter linearises an accepted camera link (link_gate.h "Linearisation"): the
// iterated-EKF point (Bell & Cathey 1993) of the pair (robot, state i) under a prior covariance
// J (order [r; i]; NavFilter passes the robot's block only, so state i stays at its mean):
//   x_{k+1} = x_0 + K_k (z - h(x_k) - H_k (x_0 - x_k)),  K_k = J H_kᵀ (H_k J H_kᵀ + R)⁻¹,
// i.e. the Gauss-Newton MAP point of this link and the prior, <= 10 steps (step < 1e-9).

#include <Eigen/Core>

#include "nav/core/models/binary_models.h"
#include "nav/core/models/measurement.h"

namespace nav::core {

inline constexpr int kLinkPairDim = 24;  ///< [x_r; x_i], 12 each
using LinkPair = Eigen::Matrix<double, kLinkPairDim, 1>;

struct LinkLinearisation {
  MeasVec h;  ///< h(x_i, x_r) at the point (CameraRelativePoseModel: a = i, b = r)
  MeasJac H_r, H_i;
  LinkPair x = LinkPair::Zero();  ///< the point [x_r; x_i]
  int iterations = 0;
};

/// Throws what the camera model throws (degenerate baseline at an iterate).
LinkLinearisation iterated_link_point(const CameraRelativePoseModel& camera,
                                      const LinkPair& x0, const Eigen::MatrixXd& prior,
                                      const MeasVec& z, const MeasCov& R);

}  // namespace nav::core
