// Relative-pose measurement models with analytic Jacobians (binary_models.h).
// Jacobians are chain products of the closed-form SSC Jacobians (pose.h).

#include "nav/core/models/binary_models.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "nav/core/geometry/pose.h"

namespace nav::core {
namespace {

/// Writes the 6-column pose Jacobian D (dim x 6) into H (dim x block), velocity columns zero.
template <class Derived>
void put_pose_jacobian(MeasJac* H, const Eigen::MatrixBase<Derived>& D, Eigen::Index block) {
  if (H == nullptr) return;
  H->setZero(D.rows(), block);
  H->leftCols(kPoseDim) = D;
}

void require_same_size(Eigen::Index a, Eigen::Index b, const char* model) {
  if (a == b) return;
  throw std::invalid_argument(std::string(model) + ": blocks a and b have different sizes (" +
                              std::to_string(a) + " and " + std::to_string(b) + ")");
}

}  // namespace

MeasVec RelativePose6Model::predict(const Eigen::Ref<const Eigen::VectorXd>& x_a,
                                    const Eigen::Ref<const Eigen::VectorXd>& x_b, MeasJac* H_a,
                                    MeasJac* H_b) const {
  require_block_size(x_a.size(), false, "RelativePose6Model");
  require_block_size(x_b.size(), false, "RelativePose6Model");
  require_same_size(x_a.size(), x_b.size(), "RelativePose6Model");
  const bool want_jacobian = H_a != nullptr || H_b != nullptr;
  Mat6x12 J;
  const Vec6 x_ab = tail_to_tail(x_a.head<6>(), x_b.head<6>(), want_jacobian ? &J : nullptr);
  put_pose_jacobian(H_a, J.leftCols<6>(), x_a.size());
  put_pose_jacobian(H_b, J.rightCols<6>(), x_b.size());
  return x_ab;
}

Vec6 CameraRelativePoseModel::camera_relative_pose(
    const Eigen::Ref<const Eigen::VectorXd>& x_a,
    const Eigen::Ref<const Eigen::VectorXd>& x_b) const {
  require_block_size(x_a.size(), false, "CameraRelativePoseModel");
  require_block_size(x_b.size(), false, "CameraRelativePoseModel");
  return tail_to_tail(head_to_tail(x_a.head<6>(), x_body_camera),
                      head_to_tail(x_b.head<6>(), x_body_camera));
}

bool CameraRelativePoseModel::baseline_is_degenerate(
    const Eigen::Ref<const Eigen::VectorXd>& x_a,
    const Eigen::Ref<const Eigen::VectorXd>& x_b) const {
  const Vec6 x_ab = camera_relative_pose(x_a, x_b);
  return !(std::hypot(x_ab[0], x_ab[1]) >= min_baseline_m);
}

MeasVec CameraRelativePoseModel::predict(const Eigen::Ref<const Eigen::VectorXd>& x_a,
                                         const Eigen::Ref<const Eigen::VectorXd>& x_b, MeasJac* H_a,
                                         MeasJac* H_b) const {
  require_block_size(x_a.size(), false, "CameraRelativePoseModel");
  require_block_size(x_b.size(), false, "CameraRelativePoseModel");
  require_same_size(x_a.size(), x_b.size(), "CameraRelativePoseModel");
  const bool want_jacobian = H_a != nullptr || H_b != nullptr;
  Mat6x12 J_ca, J_cb, J_ab;
  Mat6x12* const pj_ca = want_jacobian ? &J_ca : nullptr;
  Mat6x12* const pj_cb = want_jacobian ? &J_cb : nullptr;
  const Vec6 x_ca = head_to_tail(x_a.head<6>(), x_body_camera, pj_ca);
  const Vec6 x_cb = head_to_tail(x_b.head<6>(), x_body_camera, pj_cb);
  const Vec6 x_ab = tail_to_tail(x_ca, x_cb, want_jacobian ? &J_ab : nullptr);

  const double tx = x_ab[0], ty = x_ab[1], tz = x_ab[2];
  const double rho2 = tx * tx + ty * ty;
  const double rho = std::sqrt(rho2);
  if (!(rho >= min_baseline_m)) {
    std::ostringstream msg;
    msg << "CameraRelativePoseModel: baseline t_ab = [" << tx << ", " << ty << ", " << tz
        << "] m has |[t_x t_y]| = " << rho << " m < min_baseline_m = " << min_baseline_m
        << " m; azimuth undefined";
    throw std::domain_error(msg.str());
  }
  MeasVec z(5);
  z << std::atan2(ty, tx), std::atan2(tz, rho), x_ab[3], x_ab[4], x_ab[5];

  if (want_jacobian) {
    // G = dz / dx_ab (5x6): azimuth and elevation from t, relative angles passed through.
    const double r2 = rho2 + tz * tz;
    Eigen::Matrix<double, 5, 6> G = Eigen::Matrix<double, 5, 6>::Zero();
    G(0, 0) = -ty / rho2;
    G(0, 1) = tx / rho2;
    G(1, 0) = -tx * tz / (rho * r2);
    G(1, 1) = -ty * tz / (rho * r2);
    G(1, 2) = rho / r2;
    G.bottomRightCorner<3, 3>().setIdentity();
    const Eigen::Matrix<double, 5, 6> G_ca = G * J_ab.leftCols<6>();
    const Eigen::Matrix<double, 5, 6> G_cb = G * J_ab.rightCols<6>();
    put_pose_jacobian(H_a, G_ca * J_ca.leftCols<6>(), x_a.size());
    put_pose_jacobian(H_b, G_cb * J_cb.leftCols<6>(), x_b.size());
  }
  return z;
}

}  // namespace nav::core
