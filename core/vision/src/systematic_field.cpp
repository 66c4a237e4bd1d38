// Consider covariance of the two-view pose for smooth systematic feature displacements
// (two_view_problem.h, systematic_field_covariance).
#include <Eigen/Core>
#include <vector>

#include "two_view_problem.h"

namespace nav::vision::two_view {

namespace {

constexpr int kTerms = 6;  // 1, x, y, x^2, xy, y^2

/// Centre (the principal point) and the largest offset of one image's points from it along
/// each axis, for the basis.
struct FieldFrame {
  Eigen::Vector2d centre_px;
  Eigen::Vector2d extent_px;
};

FieldFrame frame_of(const std::vector<Eigen::Vector2d>& u, const CameraIntrinsics& cam) {
  FieldFrame f{Eigen::Vector2d(cam.cx_px, cam.cy_px), Eigen::Vector2d::Zero()};
  for (const Eigen::Vector2d& p : u)
    f.extent_px = f.extent_px.cwiseMax((p - f.centre_px).cwiseAbs());
  f.extent_px = f.extent_px.cwiseMax(1.0);
  return f;
}

/// Phi(u): 2 x 12, the displacement of u per unit coefficient (x axis terms, then y axis).
Eigen::Matrix<double, 2, 2 * kTerms> basis(const Eigen::Vector2d& u, const FieldFrame& f) {
  const Eigen::Vector2d s = (u - f.centre_px).cwiseQuotient(f.extent_px);
  Eigen::Matrix<double, 1, kTerms> m;
  m << 1.0, s.x(), s.y(), s.x() * s.x(), s.x() * s.y(), s.y() * s.y();
  Eigen::Matrix<double, 2, 2 * kTerms> phi = Eigen::Matrix<double, 2, 2 * kTerms>::Zero();
  phi.block<1, kTerms>(0, 0) = m;
  phi.block<1, kTerms>(1, kTerms) = m;
  return phi;
}

}  // namespace

Mat5 systematic_field_covariance(const std::vector<PointInformation>& info,
                                 const std::vector<Eigen::Vector2d>& u_i,
                                 const std::vector<Eigen::Vector2d>& u_j,
                                 const CameraIntrinsics& cam, double inv_sigma, const Mat5& C,
                                 double sigma_px) {
  if (!(sigma_px > 0.0) || info.empty()) return Mat5::Zero();
  const FieldFrame frame_i = frame_of(u_i, cam), frame_j = frame_of(u_j, cam);
  Eigen::Matrix<double, 5, 4 * kTerms> F = Eigen::Matrix<double, 5, 4 * kTerms>::Zero();
  for (std::size_t k = 0; k < info.size(); ++k) {
    const Eigen::Vector4d& q = info[k].q;
    F.leftCols<2 * kTerms>() += info[k].a * (q.head<2>().transpose() * basis(u_i[k], frame_i));
    F.rightCols<2 * kTerms>() += info[k].a * (q.tail<2>().transpose() * basis(u_j[k], frame_j));
  }
  const Eigen::Matrix<double, 5, 4 * kTerms> CF = (sigma_px * inv_sigma) * C * F;
  return CF * CF.transpose();
}

}  // namespace nav::vision::two_view
