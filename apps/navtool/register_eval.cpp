// Per-pair evaluation of `navtool register-eval` against the truth (register_eval.h).
#include "navtool/register_eval.h"

#include <Eigen/Cholesky>

#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "nav/core/geometry/rotation.h"
#include "nav/vision/camera_model.h"
#include "nav/vision/essential.h"
#include "nav/vision/matching.h"
#include "nav/vision/pccs.h"
#include "nav/vision/relative_pose_5dof.h"

namespace nav::tool {
namespace {

using vision::Mat5;
using vision::Mat6;
using vision::Vec5;
using vision::Vec6;

constexpr double kDeg = 180.0 / std::numbers::pi;

Mat6 stated_covariance(const PairEvalOptions& o) {
  Mat6 P = Mat6::Zero();
  const double s2 = o.prior_position_sigma_m * o.prior_position_sigma_m;
  const double a2 = o.prior_angle_sigma_rad * o.prior_angle_sigma_rad;
  P.diagonal() << s2, s2, s2, a2, a2, a2;
  return P;
}

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// Reprojection error in image j (px) of match (u_i, u_j) under the true pose: the point
/// triangulated from both rays, seen from camera j; infinite when it is not in front of both.
double true_reprojection_error_px(const Eigen::Vector2d& u_i, const Eigen::Vector2d& u_j,
                                  const vision::CameraIntrinsics& camera, const Vec6& x_i_j) {
  const Eigen::Matrix3d R_i_j = core::rotation_from_euler(x_i_j.tail<3>());
  const Eigen::Vector3d t_i_j = x_i_j.head<3>();
  const Eigen::Vector2d x_i = vision::normalised_from_pixel(camera, u_i);
  const Eigen::Vector2d x_j = vision::normalised_from_pixel(camera, u_j);
  double d_i = 0.0, d_j = 0.0;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!vision::triangulate_depths(R_i_j, t_i_j, x_i, x_j, &d_i, &d_j)) return kInf;
  if (!(d_i > 0.0 && d_j > 0.0)) return kInf;
  // The point at depth d_i on ray i, seen from camera j.
  const Eigen::Vector3d X_j = R_i_j.transpose() * (d_i * Eigen::Vector3d(x_i.x(), x_i.y(), 1.0) - t_i_j);
  if (X_j.z() <= 0.0) return kInf;
  return (vision::pixel_from_normalised(camera, X_j.head<2>() / X_j.z()) - u_j).norm();
}

/// Unconstrained matches that the true pose confirms (register_eval.h).
std::vector<vision::Match> true_correspondences(const vision::ImageFeatures& fi,
                                                const vision::ImageFeatures& fj,
                                                const vision::CameraIntrinsics& camera,
                                                const Vec6& x_i_j, double max_error_px) {
  std::vector<vision::Match> out;
  for (const vision::Match& m : vision::match_unconstrained(fi, fj).matches) {
    if (true_reprojection_error_px(fi.points_px[static_cast<std::size_t>(m.index_i)],
                                   fj.points_px[static_cast<std::size_t>(m.index_j)], camera,
                                   x_i_j) <= max_error_px)
      out.push_back(m);
  }
  return out;
}

/// Angle of the rotation between the relative rotations of two 5-DOF measurements, degrees.
double rotation_error_deg(const Vec5& z, const Vec5& z_true) {
  return Eigen::AngleAxisd(vision::rotation_from_z(z).transpose() * vision::rotation_from_z(z_true))
             .angle() *
         kDeg;
}

/// Fig. 4: true correspondences outside the PCCS band of the same prior mean with three
/// covariances (register_eval.h), into e.true_correspondences and e.missed.
void count_fig4_misses(const vision::Registration& registration, const vision::ImageFeatures& fi,
                       const vision::ImageFeatures& fj, const PairTruth& truth,
                       const vision::RelativePosePrior& prior, const PairEvalOptions& o,
                       PairEval& e) {
  const vision::CameraIntrinsics& camera = registration.camera();
  vision::PccsOptions pccs = registration.options().pccs;
  pccs.band_floor_sigma_px = 0.0;  // the band of the covariance alone (register_eval.h)
  const double scale[3] = {1.0, o.bound_inflation, 1.0 / o.overconfidence};
  const auto truths = true_correspondences(fi, fj, camera, truth.x_i_j, o.max_true_error_px);
  e.true_correspondences = static_cast<int>(truths.size());
  for (int c = 0; c < 3; ++c) {
    vision::RelativePosePrior p = prior;
    p.covariance *= scale[c];
    for (const vision::Match& m : truths) {
      const auto region = vision::search_region(fi.points_px[static_cast<std::size_t>(m.index_i)],
                                                camera, p, pccs);
      if (!region.contains(fj.points_px[static_cast<std::size_t>(m.index_j)])) ++e.missed[c];
    }
  }
}

}  // namespace

vision::RelativePosePrior make_prior(const PairTruth& truth, const PairEvalOptions& o) {
  vision::RelativePosePrior prior;
  prior.covariance = stated_covariance(o);
  std::mt19937_64 rng(o.seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(truth.i) * 1000003ULL +
                      static_cast<std::uint64_t>(truth.j));
  std::normal_distribution<double> normal(0.0, 1.0);
  Vec6 n;
  for (int k = 0; k < 6; ++k) n[k] = normal(rng);
  const Mat6 L = prior.covariance.llt().matrixL();
  prior.x_i_j = truth.x_i_j + L * n;
  const vision::SceneDepthPrior depth =
      vision::scene_depth_prior(truth.scene_depth_m, truth.scene_depth_j_m, prior.x_i_j[2],
                                o.depth_sigma_fraction, o.depth_sigma_fixed_m);
  prior.scene_depth_m = depth.depth_m;
  prior.scene_depth_sigma_m = depth.sigma_m;
  return prior;
}

PairEval evaluate_pair(const vision::Registration& registration, const vision::ImageFeatures& fi,
                       const vision::ImageFeatures& fj, const PairTruth& truth,
                       const PairEvalOptions& o, vision::RegistrationDiagnostics* diagnostics) {
  PairEval e;
  const vision::RelativePosePrior prior = make_prior(truth, o);
  const auto start = std::chrono::steady_clock::now();
  vision::RegistrationDiagnostics local;
  vision::RegistrationDiagnostics& d = diagnostics != nullptr ? *diagnostics : local;
  e.result = registration.register_pair(fi, fj, &prior, &d);
  e.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  e.residual_sigma_px = d.refinement.residual_sigma_px;
  e.inlier_area_fraction = d.refinement.inlier_area_fraction;
  e.max_leverage = d.refinement.max_leverage;
  // The refinement's inliers: how many the true pose confirms, and how closely.
  std::vector<Eigen::Vector2d> ui, uj;
  double sum_sq = 0.0;
  for (const int k : d.refinement.used_matches) {
    const vision::Match& m = d.matches.matches[static_cast<std::size_t>(k)];
    ui.push_back(fi.points_px[static_cast<std::size_t>(m.index_i)]);
    uj.push_back(fj.points_px[static_cast<std::size_t>(m.index_j)]);
    const double r = true_reprojection_error_px(ui.back(), uj.back(), registration.camera(),
                                                truth.x_i_j);
    if (r > o.max_true_error_px) continue;
    ++e.inliers_true;
    sum_sq += r * r;
  }
  if (e.inliers_true > 0) e.inliers_true_rms_px = std::sqrt(sum_sq / e.inliers_true);
  if (o.fig4) count_fig4_misses(registration, fi, fj, truth, prior, o, e);
  if (!e.result.success) return e;
  const Vec5 z_true = vision::z_from_relative_pose(truth.x_i_j);
  const Vec5& z = e.result.z;
  e.rotation_error_deg = rotation_error_deg(z, z_true);
  e.baseline_error_deg = angle_between(vision::baseline_direction(z[0], z[1]),
                                       vision::baseline_direction(z_true[0], z_true[1])) *
                         kDeg;
  const Vec5 err = vision::z_minus(z, z_true);
  e.nees = err.dot(e.result.covariance.ldlt().solve(err));
  const auto from_truth = vision::refine_two_view(
      ui, uj, registration.camera(), core::rotation_from_euler(truth.x_i_j.tail<3>()),
      truth.x_i_j.head<3>(), registration.options().refinement);
  if (from_truth.converged) {
    e.truth_start_rms_px = from_truth.reprojection_rms_px;
    e.truth_start_rotation_deg = rotation_error_deg(from_truth.z, z_true);
  }
  return e;
}

}  // namespace nav::tool
