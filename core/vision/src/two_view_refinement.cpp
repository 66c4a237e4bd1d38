// Two-view maximum-likelihood refinement (two_view_refinement.h): DLT initialisation, sparse
// Levenberg-Marquardt with the point blocks eliminated by Schur complement and Huber IRLS
// weights, and the marginal covariance of z from the final Schur complement.

#include "nav/vision/two_view_refinement.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "median.h"
#include "nav/core/geometry/rotation.h"
#include "nav/vision/relative_pose_5dof.h"
#include "two_view_problem.h"

namespace nav::vision {
namespace {

using namespace two_view;  // NOLINT(google-build-using-namespace): the private problem kernels

TwoViewRefinement fail(TwoViewRefinement out, const std::string& reason,
                       RegistrationFailure failure = RegistrationFailure::kRefinementFailed) {
  out.converged = false;
  out.failure = failure;
  out.reason = "two-view refinement: " + reason;
  return out;
}

using detail::median;

/// 12 sqrt(det(second moment of the points)) / frame area (two_view_refinement.h).
double area_fraction(const std::vector<Eigen::Vector2d>& u_px, const CameraIntrinsics& cam) {
  // A camera without an expected size: the frame whose centre is the principal point.
  const double width = cam.width_px > 0 ? cam.width_px : 2.0 * cam.cx_px;
  const double height = cam.height_px > 0 ? cam.height_px : 2.0 * cam.cy_px;
  if (u_px.size() < 3 || !(width > 0.0) || !(height > 0.0)) return 0.0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& u : u_px) mean += u;
  mean /= static_cast<double>(u_px.size());
  Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
  for (const auto& u : u_px) second += (u - mean) * (u - mean).transpose();
  second /= static_cast<double>(u_px.size());
  return 12.0 * std::sqrt(std::max(0.0, second.determinant())) / (width * height);
}

/// 1.4826 x the median residual norm of a match, in pixels, from each match's whitened
/// residual norms [|r_i|, |r_j|] (two_view_refinement.h: one degree of freedom per match once
/// its point is fitted, so the norm is sigma |N(0, 1)|).
double robust_sigma_px(const std::vector<Eigen::Vector2d>& whitened_norms, double pixel_sigma_px) {
  std::vector<double> norm(whitened_norms.size());
  for (std::size_t k = 0; k < norm.size(); ++k) norm[k] = whitened_norms[k].norm();
  return norm.empty() ? pixel_sigma_px : 1.4826 * pixel_sigma_px * median(norm);
}

}  // namespace

void set_pixel_sigma_keeping_parallax_floor(TwoViewRefinementOptions& options,
                                            double pixel_sigma_px) {
  options.min_parallax_sigma *= options.pixel_sigma_px / pixel_sigma_px;
  options.pixel_sigma_px = pixel_sigma_px;
}

Eigen::VectorXd two_view_residuals(const Vec5& z, const std::vector<Eigen::Vector3d>& points_i,
                                   const std::vector<Eigen::Vector2d>& u_i_px,
                                   const std::vector<Eigen::Vector2d>& u_j_px,
                                   const CameraIntrinsics& camera, double pixel_sigma_px) {
  std::vector<Eigen::Vector3d> p(points_i.size());
  for (std::size_t k = 0; k < points_i.size(); ++k) p[k] = to_inverse_depth(points_i[k]);
  return stacked_residuals(pose_from_z(z), p, u_i_px, u_j_px, camera, 1.0 / pixel_sigma_px);
}

TwoViewRefinement refine_two_view(const std::vector<Eigen::Vector2d>& u_i_px,
                                  const std::vector<Eigen::Vector2d>& u_j_px,
                                  const CameraIntrinsics& cam, const Eigen::Matrix3d& R_i_j_initial,
                                  const Eigen::Vector3d& t_i_j_initial,
                                  const TwoViewRefinementOptions& opt) {
  TwoViewRefinement out;
  std::ostringstream why;
  if (u_i_px.size() != u_j_px.size()) {
    why << u_i_px.size() << " points in image i but " << u_j_px.size() << " in image j";
    return fail(out, why.str());
  }
  if (!(cam.fx_px > 0.0) || !(cam.fy_px > 0.0) || !(opt.pixel_sigma_px > 0.0)) {
    why << "focal lengths and pixel sigma must be positive (fx " << cam.fx_px << ", fy "
        << cam.fy_px << ", sigma " << opt.pixel_sigma_px << ")";
    return fail(out, why.str());
  }
  const int n_in = static_cast<int>(u_i_px.size());
  if (n_in < opt.min_points) {
    why << n_in << " matches, fewer than the " << opt.min_points << " needed";
    return fail(out, why.str(), RegistrationFailure::kTooFewInliers);
  }
  if (!(t_i_j_initial.norm() > 0.0) || !t_i_j_initial.allFinite() || !R_i_j_initial.allFinite()) {
    why << "initial pose has no baseline direction (t = [" << t_i_j_initial.transpose() << "])";
    return fail(out, why.str());
  }
  PoseState x;
  x.rpy = core::euler_from_rotation(R_i_j_initial);
  x.t = t_i_j_initial.normalized();

  const double focal_px = 0.5 * (cam.fx_px + cam.fy_px);
  const double min_parallax_px = opt.min_parallax_sigma * opt.pixel_sigma_px;
  const auto normalised = [&cam](const Eigen::Vector2d& u) {
    return Eigen::Vector2d((u.x() - cam.cx_px) / cam.fx_px, (u.y() - cam.cy_px) / cam.fy_px);
  };
  {
    // Parallax before anything else: the angle between the two viewing rays of each match
    // (ray j rotated into camera i) is ~0 for a pure rotation, whatever the initial baseline.
    // In pixels at the mean focal length, comparable with the feature noise.
    const Eigen::Matrix3d R = core::rotation_from_euler(x.rpy);
    std::vector<double> ray_angle_px(static_cast<std::size_t>(n_in));
    for (int k = 0; k < n_in; ++k) {
      const Eigen::Vector3d a = normalised(u_i_px[k]).homogeneous();
      const Eigen::Vector3d bb = R * normalised(u_j_px[k]).homogeneous();
      ray_angle_px[k] = std::atan2(a.cross(bb).norm(), a.dot(bb)) * focal_px;
    }
    const double m = median(ray_angle_px);
    if (!(m >= min_parallax_px)) {
      why << "median derotated parallax " << m << " px below " << min_parallax_px << " px ("
          << opt.min_parallax_sigma << " pixel sigmas) with the initial rotation: pure rotation "
          << "or a baseline too short for the scene";
      return fail(out, why.str());
    }
  }

  // Linear triangulation with the initial pose; matches behind either camera are dropped.
  // X holds the inverse-depth points from here on.
  std::vector<Eigen::Vector3d> X;
  std::vector<Eigen::Vector2d> ui, uj;
  {
    const PoseTerms pose(x);
    for (int k = 0; k < n_in; ++k) {
      const Eigen::Vector3d p =
          triangulate(normalised(u_i_px[k]), normalised(u_j_px[k]), pose.R_j_i, pose.t);
      const double depth_j = (pose.R_j_i * (p - pose.t)).z();
      if (!p.allFinite() || !(p.z() > 0.0) || !(depth_j > 0.0)) {
        ++out.behind_camera;
        continue;
      }
      X.push_back(to_inverse_depth(p));
      ui.push_back(u_i_px[k]);
      uj.push_back(u_j_px[k]);
      out.used_matches.push_back(k);
    }
  }
  if (out.behind_camera > opt.max_fraction_behind * n_in) {
    why << out.behind_camera << " of " << n_in
        << " matches triangulate behind camera i or j with the initial pose (baseline "
           "direction or rotation inconsistent with the matches)";
    return fail(out, why.str());
  }
  if (static_cast<int>(X.size()) < opt.min_points) {
    why << X.size() << " matches in front of both cameras, fewer than the " << opt.min_points
        << " needed";
    return fail(out, why.str(), RegistrationFailure::kTooFewInliers);
  }

  // Robust LM, then the matches whose residual in either image exceeds the Huber kink are
  // rejected and the rest re-solved (at most kRounds times): with gross mismatches a robust
  // loss alone converges slowly (their points drift along a flat valley of the cost) and
  // leaves down-weighted terms in the information; after rejection every weight is 1.
  const double inv_sigma = 1.0 / opt.pixel_sigma_px;
  double c = opt.huber_threshold_sigma;  // whitened; raised to the measured noise after round 0
  const std::size_t n_front = X.size();
  out.initial_rms_px =
      opt.pixel_sigma_px * std::sqrt(stacked_residuals(x, X, ui, uj, cam, inv_sigma).squaredNorm() /
                                     static_cast<double>(4 * n_front));
  // Fills the solution's numbers into `out` (also for failures after the solve, as diagnosis).
  const auto summarise = [&]() {
    const std::size_t n = X.size();
    const PoseTerms pose(x);
    out.R_i_j = pose.R_j_i.transpose();
    out.t_i_j_unit = pose.t;
    std::vector<double> parallax(n);
    out.points_i.resize(n);
    out.depths_i.resize(n);
    out.depths_j.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      // rho <= 0: at or beyond infinity, i.e. behind camera i; the depths say so by their sign.
      const Eigen::Vector3d m(X[k].x(), X[k].y(), 1.0);
      const double rho = X[k].z();
      out.points_i[k] = from_inverse_depth(X[k]);
      out.depths_i[k] = 1.0 / rho;
      out.depths_j[k] = (pose.R_j_i * (m - rho * pose.t)).z() / rho;
      const Eigen::Vector3d bb = m - rho * pose.t;  // ray of camera j, scaled by rho
      parallax[k] = std::atan2(m.cross(bb).norm(), m.dot(bb)) * focal_px;
    }
    const double rss_whitened = stacked_residuals(x, X, ui, uj, cam, inv_sigma).squaredNorm();
    out.reprojection_rms_px =
        opt.pixel_sigma_px * std::sqrt(rss_whitened / static_cast<double>(4 * n));
    // 4n residuals, 3n + 5 parameters: n - 5 degrees of freedom (n >= min_points >= 8 > 5).
    out.residual_sigma_px =
        opt.pixel_sigma_px *
        std::sqrt(rss_whitened / static_cast<double>(std::max<std::size_t>(n - 5, 1)));
    out.median_parallax_px = median(parallax);
    out.inlier_area_fraction = area_fraction(ui, cam);
  };
  constexpr int kRounds = 3;
  NormalEquations ne;
  for (int round = 0;; ++round) {
    const LmOutcome lm = levenberg_marquardt(x, X, ui, uj, cam, inv_sigma, c, opt, ne);
    out.iterations += lm.iterations;
    if (!lm.error.empty()) {
      summarise();
      why << lm.error << "; median parallax " << out.median_parallax_px << " px";
      return fail(out, why.str());
    }
    // Each match's whitened residual norms in image i and j at this round's solution.
    const PoseTerms pose(x);
    std::vector<Eigen::Vector2d> norms(X.size());
    for (std::size_t k = 0; k < X.size(); ++k) {
      const PointResidual p = point_residual(pose, cam, X[k], ui[k], uj[k], inv_sigma, false);
      norms[k] << p.r_i.norm(), p.r_j.norm();
    }
    const double lm_kink = c;
    if (round == 0) {
      out.robust_sigma_px = robust_sigma_px(norms, opt.pixel_sigma_px);
      if (opt.kink_at_measured_noise) c *= std::max(1.0, out.robust_sigma_px * inv_sigma);
    }
    // Keep the matches inside the Huber kink in both images and in front of both cameras
    // (inverse depth rho > 0; a distant point may cross infinity within its noise).
    std::vector<std::size_t> keep;
    bool kept_beyond_lm_kink = false;  // down-weighted by this round's solve
    for (std::size_t k = 0; k < X.size(); ++k) {
      const double rho = X[k].z();
      const Eigen::Vector3d m(X[k].x(), X[k].y(), 1.0);
      if (!(rho > 0.0) || !((pose.R_j_i * (m - rho * pose.t)).z() > 0.0)) {
        ++out.behind_camera;
      } else if (norms[k].maxCoeff() > c) {
        ++out.rejected_outliers;
      } else {
        keep.push_back(k);
        kept_beyond_lm_kink |= norms[k].maxCoeff() > lm_kink;
      }
    }
    // A kink raised after round 0 keeps matches that round's solve down-weighted: solve again
    // with unit weights even when nothing was dropped.
    if (keep.size() == X.size() && kept_beyond_lm_kink) continue;
    if (keep.size() == X.size()) {
      if (lm.converged) break;
      summarise();
      why << "no convergence within " << opt.max_iterations
          << " iterations (last relative cost decrease " << lm.last_relative_decrease
          << "); median parallax " << out.median_parallax_px << " px";
      return fail(out, why.str());
    }
    const int n_dropped = static_cast<int>(n_front - keep.size());
    if (round + 1 >= kRounds || n_dropped > opt.max_fraction_outliers * n_front ||
        static_cast<int>(keep.size()) < opt.min_points) {
      why << out.rejected_outliers << " of " << n_front << " matches rejected as outliers and "
          << out.behind_camera << " behind a camera (" << keep.size() << " left after " << round + 1
          << " rounds)";
      return fail(out, why.str(), RegistrationFailure::kTooFewInliers);
    }
    std::vector<Eigen::Vector3d> X_keep;
    std::vector<Eigen::Vector2d> ui_keep, uj_keep;
    std::vector<int> used_keep;
    for (const std::size_t k : keep) {
      X_keep.push_back(X[k]);
      ui_keep.push_back(ui[k]);
      uj_keep.push_back(uj[k]);
      used_keep.push_back(out.used_matches[k]);
    }
    X = std::move(X_keep);
    ui = std::move(ui_keep);
    uj = std::move(uj_keep);
    out.used_matches = std::move(used_keep);
  }
  summarise();
  if (!(out.median_parallax_px >= min_parallax_px)) {
    why << "median parallax " << out.median_parallax_px << " px below " << min_parallax_px
        << " px after refinement: pure rotation or a baseline too short for the scene";
    return fail(out, why.str());
  }

  Mat5x6 G;  // dz / d[t; rpy]
  try {
    Vec6 x_i_j;
    x_i_j << x.t, x.rpy;
    out.z = z_from_relative_pose(x_i_j, &G);
  } catch (const std::domain_error& e) {
    return fail(out, std::string("refined baseline along the optical axis: ") + e.what());
  }

  // Marginal covariance: inverse of the undamped Schur complement at the solution, in the
  // solver's delta = [b; d_rpy], mapped to z with J = blockdiag(d(az, el)/dt B, I3).
  Mat5 S;
  Vec5 b;
  std::vector<Eigen::Matrix3d> C_inv;
  if (!schur(ne, 0.0, S, b, C_inv)) return fail(out, "a point's information is singular");
  const Eigen::SelfAdjointEigenSolver<Mat5> eig(S);
  const double ev_min = eig.eigenvalues()[0], ev_max = eig.eigenvalues()[4];
  if (!(ev_min > opt.min_rcond * ev_max)) {
    why << "information of the pose is singular (eigenvalues " << ev_min << " .. " << ev_max
        << "): baseline direction or rotation unobservable; median parallax "
        << out.median_parallax_px << " px";
    return fail(out, why.str());
  }
  const Mat5 covariance_delta = eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() *
                                eig.eigenvectors().transpose();
  const std::vector<PointInformation> info = point_information(x, X, ui, uj, cam, inv_sigma);
  const ReliabilityBound reliability =
      reliability_bound(info, covariance_delta, opt.reliability_delta0, opt.reliability_group);
  out.max_leverage = reliability.max_leverage;
  for (const std::size_t k : reliability.group)
    out.reliability_matches.push_back(out.used_matches[k]);
  Mat5 J = Mat5::Zero();
  J.topLeftCorner<2, 2>() = G.topLeftCorner<2, 3>() * tangent_basis(x.t);
  J.bottomRightCorner<3, 3>().setIdentity();
  if (opt.scale_by_residual_variance) {
    const double ratio = opt.residual_sigma_factor * out.residual_sigma_px / opt.pixel_sigma_px;
    out.covariance_scale = std::max(1.0, ratio * ratio);
  }
  out.information_covariance = out.covariance_scale * J * covariance_delta * J.transpose();
  out.reliability_covariance = out.covariance_scale * J * reliability.covariance * J.transpose();
  const double systematic_px =
      opt.systematic_sigma_px + opt.systematic_noise_fraction * out.robust_sigma_px;
  const Mat5 systematic_delta =
      systematic_field_covariance(info, ui, uj, cam, inv_sigma, covariance_delta, systematic_px);
  out.systematic_covariance = J * systematic_delta * J.transpose();
  out.covariance = out.information_covariance + out.reliability_covariance +
                   out.systematic_covariance +
                   opt.model_sigma_rad * opt.model_sigma_rad * Mat5::Identity();
  out.converged = true;
  return out;
}

TwoViewRefinement refine_two_view(const ImageFeatures& i, const ImageFeatures& j,
                                  const PutativeMatches& matches, const EssentialEstimate& estimate,
                                  const CameraIntrinsics& camera,
                                  const TwoViewRefinementOptions& options) {
  if (!estimate.ok) {
    return fail(TwoViewRefinement{}, "essential-matrix estimate not usable: " + estimate.reason,
                RegistrationFailure::kEssentialFailed);
  }
  std::vector<Eigen::Vector2d> u_i, u_j;
  std::vector<int> index;
  for (const int m : estimate.inliers) {
    const bool in_range = m >= 0 && m < static_cast<int>(matches.matches.size());
    const Match* match = in_range ? &matches.matches[static_cast<std::size_t>(m)] : nullptr;
    if (match == nullptr || match->index_i < 0 || match->index_j < 0 ||
        match->index_i >= static_cast<int>(i.size()) ||
        match->index_j >= static_cast<int>(j.size())) {
      std::ostringstream why;
      why << "inlier " << m << " does not name a match of " << matches.matches.size() << " between "
          << i.size() << " and " << j.size() << " features";
      return fail(TwoViewRefinement{}, why.str());
    }
    u_i.push_back(i.points_px[static_cast<std::size_t>(match->index_i)]);
    u_j.push_back(j.points_px[static_cast<std::size_t>(match->index_j)]);
    index.push_back(m);
  }
  TwoViewRefinement out =
      refine_two_view(u_i, u_j, camera, estimate.R_i_j, estimate.t_i_j_unit, options);
  for (int& k : out.used_matches) k = index[static_cast<std::size_t>(k)];
  return out;
}

}  // namespace nav::vision
