#pragma once
// Synthetic two-view scenes with known truth for the vision tests: a seafloor of random points
// around a depth in camera i, the 1280x1024 fx = fy = 1000 camera of config/sim.yaml, and
// noisy pixel observations of the points visible in both images.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "nav/core/geometry/pose.h"
#include "nav/vision/vision_types.h"
#include "test_cameras.h"

namespace nav::vision::test {

inline double deg(double d) { return d * std::numbers::pi / 180.0; }

/// Camera j in camera i: 0.7 m lateral, small tilt, 8 deg yaw (a survey leg neighbour).
inline Vec6 default_x_i_j() {
  Vec6 x;
  x << 0.7, 0.25, 0.05, deg(2.0), deg(-1.5), deg(8.0);
  return x;
}

inline Eigen::Vector2d project(const CameraIntrinsics& c, const Eigen::Vector3d& X) {
  return {c.fx_px * X.x() / X.z() + c.cx_px, c.fy_px * X.y() / X.z() + c.cy_px};
}

inline bool in_image(const CameraIntrinsics& c, const Eigen::Vector2d& u) {
  return u.x() >= 0.0 && u.y() >= 0.0 && u.x() < c.width_px && u.y() < c.height_px;
}

struct TwoViewScene {
  CameraIntrinsics camera;
  Vec6 x_i_j = Vec6::Zero();
  std::vector<Eigen::Vector3d> points_i;  ///< Truth, camera i, metres.
  std::vector<Eigen::Vector2d> u_i, u_j;  ///< Noisy observations.
  std::vector<Eigen::Vector2d> u_i_true, u_j_true;
  std::size_t size() const { return points_i.size(); }
};

/// n points seen by both cameras: pixel of camera i uniform over the image, depth in camera i
/// drawn from N(depth_m, depth_sigma_m^2), kept when it projects into image j in front of it.
inline TwoViewScene make_scene(std::mt19937& rng, const Vec6& x_i_j, int n, double depth_m,
                               double depth_sigma_m, double pixel_sigma_px) {
  TwoViewScene s;
  s.camera = sim_camera();
  s.x_i_j = x_i_j;
  const Eigen::Matrix3d R = core::pose_rotation(x_i_j);
  const Eigen::Vector3d t = core::pose_translation(x_i_j);
  std::uniform_real_distribution<double> ux(0.0, s.camera.width_px), uy(0.0, s.camera.height_px);
  std::normal_distribution<double> depth(depth_m, depth_sigma_m), n01(0.0, 1.0);
  while (static_cast<int>(s.size()) < n) {
    const Eigen::Vector2d u(ux(rng), uy(rng));
    const double d = depth(rng);
    if (d <= 0.1) continue;
    const Eigen::Vector3d X_i(d * (u.x() - s.camera.cx_px) / s.camera.fx_px,
                              d * (u.y() - s.camera.cy_px) / s.camera.fy_px, d);
    const Eigen::Vector3d X_j = R.transpose() * (X_i - t);
    if (X_j.z() <= 0.1) continue;
    const Eigen::Vector2d v = project(s.camera, X_j);
    if (!in_image(s.camera, v)) continue;
    s.points_i.push_back(X_i);
    s.u_i_true.push_back(u);
    s.u_j_true.push_back(v);
    s.u_i.push_back(u + pixel_sigma_px * Eigen::Vector2d(n01(rng), n01(rng)));
    s.u_j.push_back(v + pixel_sigma_px * Eigen::Vector2d(n01(rng), n01(rng)));
  }
  return s;
}

/// A draw from N(0, P).
inline Vec6 draw(std::mt19937& rng, const Mat6& P) {
  std::normal_distribution<double> n01;
  Vec6 e;
  for (int k = 0; k < 6; ++k) e[k] = n01(rng);
  return Eigen::LLT<Mat6>(P).matrixL() * e;
}

/// Prior covariance of the tests: 5 cm / 3 cm in translation, 1 deg roll/pitch, 2 deg heading.
inline Mat6 default_prior_covariance() {
  Vec6 sigma;
  sigma << 0.05, 0.05, 0.03, deg(1.0), deg(1.0), deg(2.0);
  return sigma.cwiseProduct(sigma).asDiagonal();
}

}  // namespace nav::vision::test
