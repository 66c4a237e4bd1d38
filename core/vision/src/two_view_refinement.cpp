// Two-view maximum-likelihood refinement (two_view_refinement.h): DLT initialisation, sparse
// Levenberg-Marquardt with the point blocks eliminated by Schur complement and Huber IRLS
// weights, and the marginal covariance of z from the final Schur complement.

#include "nav/vision/two_view_refinement.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "nav/core/geometry/rotation.h"
#include "nav/vision/relative_pose_5dof.h"

namespace nav::vision {
namespace {

using Mat23 = Eigen::Matrix<double, 2, 3>;
using Mat25 = Eigen::Matrix<double, 2, 5>;
using Mat53 = Eigen::Matrix<double, 5, 3>;

/// Pose-dependent quantities of z shared by every point.
struct PoseTerms {
  Eigen::Matrix3d R_j_i;                  // R_i_j^T
  std::array<Eigen::Matrix3d, 3> dR_j_i;  // d(R_i_j^T) / d(roll, pitch, heading)
  Eigen::Vector3d t;                      // unit baseline t_i_j
  Mat3x2 dt;                              // d t / d(azimuth, elevation)

  explicit PoseTerms(const Vec5& z) {
    const Eigen::Vector3d rpy = z.tail<3>();
    R_j_i = core::rotation_from_euler(rpy).transpose();
    dR_j_i[0] = core::dR_droll(rpy).transpose();
    dR_j_i[1] = core::dR_dpitch(rpy).transpose();
    dR_j_i[2] = core::dR_dheading(rpy).transpose();
    t = baseline_direction(z[0], z[1], &dt);
  }
};

/// Projection in pixels and its Jacobian with respect to the camera-frame point.
Eigen::Vector2d project(const CameraIntrinsics& c, const Eigen::Vector3d& X, Mat23* J) {
  const double iz = 1.0 / X.z();
  if (J != nullptr) {
    *J << c.fx_px * iz, 0.0, -c.fx_px * X.x() * iz * iz,  //
        0.0, c.fy_px * iz, -c.fy_px * X.y() * iz * iz;
  }
  return {c.fx_px * X.x() * iz + c.cx_px, c.fy_px * X.y() * iz + c.cy_px};
}

/// Whitened residuals of one point in both images, with Jacobians when asked.
struct PointResidual {
  Eigen::Vector2d r_i, r_j;
  Mat23 J_i_X, J_j_X;
  Mat25 J_j_z;
};

PointResidual point_residual(const PoseTerms& pose, const CameraIntrinsics& cam,
                             const Eigen::Vector3d& X, const Eigen::Vector2d& u_i,
                             const Eigen::Vector2d& u_j, double inv_sigma, bool jacobians) {
  PointResidual out;
  Mat23 Jp_i, Jp_j;
  const Eigen::Vector3d w = X - pose.t;
  const Eigen::Vector3d X_j = pose.R_j_i * w;
  out.r_i = (project(cam, X, &Jp_i) - u_i) * inv_sigma;
  out.r_j = (project(cam, X_j, &Jp_j) - u_j) * inv_sigma;
  if (jacobians) {
    out.J_i_X = Jp_i * inv_sigma;
    out.J_j_X = Jp_j * pose.R_j_i * inv_sigma;
    Eigen::Matrix<double, 3, 5> dXj_dz;
    dXj_dz.leftCols<2>() = -pose.R_j_i * pose.dt;
    for (int a = 0; a < 3; ++a) dXj_dz.col(2 + a) = pose.dR_j_i[a] * w;
    out.J_j_z = Jp_j * dXj_dz * inv_sigma;
  }
  return out;
}

/// Huber: rho(s) for s = |r|^2 of one 2-vector observation, and the IRLS weight rho'(s).
double huber_rho(double s, double c) { return s <= c * c ? s : 2.0 * c * std::sqrt(s) - c * c; }
double huber_weight(double s, double c) { return s <= c * c ? 1.0 : c / std::sqrt(s); }

/// Linear triangulation (Hartley & Zisserman 12.2) in camera i from normalised coordinates.
Eigen::Vector3d triangulate(const Eigen::Vector2d& x_i, const Eigen::Vector2d& x_j,
                            const Eigen::Matrix3d& R_j_i, const Eigen::Vector3d& t_i_j) {
  Eigen::Matrix<double, 3, 4> P_j;
  P_j.leftCols<3>() = R_j_i;
  P_j.col(3) = -R_j_i * t_i_j;
  Eigen::Matrix4d A;
  A.row(0) << -1.0, 0.0, x_i.x(), 0.0;
  A.row(1) << 0.0, -1.0, x_i.y(), 0.0;
  A.row(2) = x_j.x() * P_j.row(2) - P_j.row(0);
  A.row(3) = x_j.y() * P_j.row(2) - P_j.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d h = svd.matrixV().col(3);
  return h.head<3>() / h[3];
}

/// Normal equations of the (robust) whitened problem: pose block, point blocks, couplings.
struct NormalEquations {
  Mat5 H_zz = Mat5::Zero();
  Vec5 g_z = Vec5::Zero();
  std::vector<Eigen::Matrix3d> H_kk;
  std::vector<Mat53> H_zk;
  std::vector<Eigen::Vector3d> g_k;
  double cost = 0.0;  // sum of rho
};

NormalEquations build(const Vec5& z, const std::vector<Eigen::Vector3d>& X,
                      const std::vector<Eigen::Vector2d>& u_i,
                      const std::vector<Eigen::Vector2d>& u_j, const CameraIntrinsics& cam,
                      double inv_sigma, double huber_c) {
  const PoseTerms pose(z);
  NormalEquations ne;
  ne.H_kk.resize(X.size());
  ne.H_zk.resize(X.size());
  ne.g_k.resize(X.size());
  for (std::size_t k = 0; k < X.size(); ++k) {
    const PointResidual p = point_residual(pose, cam, X[k], u_i[k], u_j[k], inv_sigma, true);
    const double s_i = p.r_i.squaredNorm(), s_j = p.r_j.squaredNorm();
    const double w_i = huber_weight(s_i, huber_c), w_j = huber_weight(s_j, huber_c);
    ne.cost += huber_rho(s_i, huber_c) + huber_rho(s_j, huber_c);
    ne.H_kk[k] = w_i * p.J_i_X.transpose() * p.J_i_X + w_j * p.J_j_X.transpose() * p.J_j_X;
    ne.g_k[k] = w_i * p.J_i_X.transpose() * p.r_i + w_j * p.J_j_X.transpose() * p.r_j;
    ne.H_zk[k] = w_j * p.J_j_z.transpose() * p.J_j_X;
    ne.H_zz += w_j * p.J_j_z.transpose() * p.J_j_z;
    ne.g_z += w_j * p.J_j_z.transpose() * p.r_j;
  }
  return ne;
}

double robust_cost(const Vec5& z, const std::vector<Eigen::Vector3d>& X,
                   const std::vector<Eigen::Vector2d>& u_i, const std::vector<Eigen::Vector2d>& u_j,
                   const CameraIntrinsics& cam, double inv_sigma, double huber_c) {
  const PoseTerms pose(z);
  double cost = 0.0;
  for (std::size_t k = 0; k < X.size(); ++k) {
    const PointResidual p = point_residual(pose, cam, X[k], u_i[k], u_j[k], inv_sigma, false);
    cost += huber_rho(p.r_i.squaredNorm(), huber_c) + huber_rho(p.r_j.squaredNorm(), huber_c);
  }
  return cost;
}

/// Schur complement S = H_zz - sum H_zk H_kk^-1 H_kz (with damping lambda on every diagonal,
/// Marquardt scaling) and the reduced right-hand side; false when a point block is singular.
bool schur(const NormalEquations& ne, double lambda, Mat5& S, Vec5& b,
           std::vector<Eigen::Matrix3d>& H_kk_inv) {
  S = ne.H_zz;
  S.diagonal() += lambda * ne.H_zz.diagonal().cwiseMax(1e-12);
  b = -ne.g_z;
  H_kk_inv.resize(ne.H_kk.size());
  for (std::size_t k = 0; k < ne.H_kk.size(); ++k) {
    Eigen::Matrix3d C = ne.H_kk[k];
    C.diagonal() += lambda * ne.H_kk[k].diagonal().cwiseMax(1e-12);
    bool invertible = false;
    C.computeInverseWithCheck(H_kk_inv[k], invertible, 1e-300);
    if (!invertible || !H_kk_inv[k].allFinite()) return false;
    S -= ne.H_zk[k] * H_kk_inv[k] * ne.H_zk[k].transpose();
    b += ne.H_zk[k] * H_kk_inv[k] * ne.g_k[k];
  }
  S = 0.5 * (S + S.transpose()).eval();
  return S.allFinite() && b.allFinite();
}

/// Keeps z in its canonical ranges (azimuth, angles wrapped; elevation in [-pi/2, pi/2]).
Vec5 canonical(const Vec5& z) { return z_from_relative_pose(relative_pose_from_z(z, 1.0)); }

struct LmOutcome {
  int iterations = 0;
  bool converged = false;
  double last_relative_decrease = 1.0;
  std::string error;  // non-empty: numerical failure
};

/// Sparse Levenberg-Marquardt (Hartley & Zisserman A6.3) from (z, X); `ne` returns the
/// normal equations at the final (z, X).
LmOutcome levenberg_marquardt(Vec5& z, std::vector<Eigen::Vector3d>& X,
                              const std::vector<Eigen::Vector2d>& ui,
                              const std::vector<Eigen::Vector2d>& uj, const CameraIntrinsics& cam,
                              double inv_sigma, double c, const TwoViewRefinementOptions& opt,
                              NormalEquations& ne) {
  LmOutcome out;
  const std::size_t n = X.size();
  double lambda = 1e-4;
  ne = build(z, X, ui, uj, cam, inv_sigma, c);
  std::vector<Eigen::Matrix3d> C_inv;
  for (; out.iterations < opt.max_iterations && !out.converged; ++out.iterations) {
    Mat5 S;
    Vec5 b;
    if (!schur(ne, lambda, S, b, C_inv)) {
      out.error = "a point's information is singular";
      return out;
    }
    const Vec5 dz = S.ldlt().solve(b);
    if (!dz.allFinite()) {
      out.error = "the reduced normal equations are singular";
      return out;
    }
    std::vector<Eigen::Vector3d> X_new(n);
    double step2 = dz.squaredNorm();
    for (std::size_t k = 0; k < n; ++k) {
      const Eigen::Vector3d dx = -C_inv[k] * (ne.g_k[k] + ne.H_zk[k].transpose() * dz);
      X_new[k] = X[k] + dx;
      step2 += dx.squaredNorm();
    }
    const Vec5 z_new = canonical(z + dz);
    const double cost_new = robust_cost(z_new, X_new, ui, uj, cam, inv_sigma, c);
    if (std::isfinite(cost_new) && cost_new <= ne.cost) {
      out.last_relative_decrease = (ne.cost - cost_new) / std::max(ne.cost, 1e-300);
      z = z_new;
      X = std::move(X_new);
      ne = build(z, X, ui, uj, cam, inv_sigma, c);
      lambda = std::max(lambda / 10.0, 1e-12);
      // Pose step in standard deviations of z (S-norm): stops once z no longer moves even if
      // the points of down-weighted mismatches still drift.
      const double pose_step_sigma = std::sqrt(std::max(0.0, dz.dot(S * dz)));
      out.converged = out.last_relative_decrease < opt.function_tolerance ||
                      std::sqrt(step2) < opt.parameter_tolerance ||
                      pose_step_sigma < opt.pose_step_tolerance_sigma;
    } else {
      lambda *= 10.0;
      // No descent left along any damped direction: a minimum.
      out.converged = lambda > 1e12 || std::sqrt(step2) < opt.parameter_tolerance;
    }
  }
  return out;
}

TwoViewRefinement fail(TwoViewRefinement out, const std::string& reason,
                       RegistrationFailure failure = RegistrationFailure::kRefinementFailed) {
  out.converged = false;
  out.failure = failure;
  out.reason = "two-view refinement: " + reason;
  return out;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

Eigen::VectorXd two_view_residuals(const Vec5& z, const std::vector<Eigen::Vector3d>& points_i,
                                   const std::vector<Eigen::Vector2d>& u_i_px,
                                   const std::vector<Eigen::Vector2d>& u_j_px,
                                   const CameraIntrinsics& camera, double pixel_sigma_px) {
  const PoseTerms pose(z);
  Eigen::VectorXd r(4 * static_cast<Eigen::Index>(points_i.size()));
  for (std::size_t k = 0; k < points_i.size(); ++k) {
    const PointResidual p = point_residual(pose, camera, points_i[k], u_i_px[k], u_j_px[k],
                                           1.0 / pixel_sigma_px, false);
    r.segment<2>(4 * static_cast<Eigen::Index>(k)) = p.r_i;
    r.segment<2>(4 * static_cast<Eigen::Index>(k) + 2) = p.r_j;
  }
  return r;
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
  Vec5 z;
  try {
    z = z_from_rotation_translation(R_i_j_initial, t_i_j_initial);
  } catch (const std::domain_error& e) {
    return fail(out, std::string("initial pose: ") + e.what());
  }

  const auto normalised = [&cam](const Eigen::Vector2d& u) {
    return Eigen::Vector2d((u.x() - cam.cx_px) / cam.fx_px, (u.y() - cam.cy_px) / cam.fy_px);
  };
  {
    // Parallax before anything else: the angle between the two viewing rays of each match
    // (ray j rotated into camera i) is ~0 for a pure rotation, whatever the initial baseline.
    const Eigen::Matrix3d R = rotation_from_z(z);
    std::vector<double> ray_angle(static_cast<std::size_t>(n_in));
    for (int k = 0; k < n_in; ++k) {
      const Eigen::Vector3d a = normalised(u_i_px[k]).homogeneous();
      const Eigen::Vector3d bb = R * normalised(u_j_px[k]).homogeneous();
      ray_angle[k] = std::atan2(a.cross(bb).norm(), a.dot(bb)) * 180.0 / std::numbers::pi;
    }
    const double m = median(ray_angle);
    if (!(m >= opt.min_parallax_deg)) {
      why << "median ray angle " << m << " deg below " << opt.min_parallax_deg
          << " deg with the initial rotation (pure rotation or no baseline)";
      return fail(out, why.str());
    }
  }

  // Linear triangulation with the initial pose; matches behind either camera are dropped.
  std::vector<Eigen::Vector3d> X;
  std::vector<Eigen::Vector2d> ui, uj;
  {
    const PoseTerms pose(z);
    for (int k = 0; k < n_in; ++k) {
      const Eigen::Vector3d p =
          triangulate(normalised(u_i_px[k]), normalised(u_j_px[k]), pose.R_j_i, pose.t);
      const double depth_j = (pose.R_j_i * (p - pose.t)).z();
      if (!p.allFinite() || !(p.z() > 0.0) || !(depth_j > 0.0)) {
        ++out.behind_camera;
        continue;
      }
      X.push_back(p);
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
  const double c = opt.huber_threshold_sigma;
  const std::size_t n_front = X.size();
  out.initial_rms_px =
      opt.pixel_sigma_px *
      std::sqrt(two_view_residuals(z, X, ui, uj, cam, opt.pixel_sigma_px).squaredNorm() /
                static_cast<double>(4 * n_front));
  constexpr int kRounds = 3;
  NormalEquations ne;
  for (int round = 0;; ++round) {
    const LmOutcome lm = levenberg_marquardt(z, X, ui, uj, cam, inv_sigma, c, opt, ne);
    out.iterations += lm.iterations;
    if (!lm.error.empty()) return fail(out, lm.error);
    std::vector<std::size_t> keep;
    const PoseTerms pose(z);
    for (std::size_t k = 0; k < X.size(); ++k) {
      const PointResidual p = point_residual(pose, cam, X[k], ui[k], uj[k], inv_sigma, false);
      if (std::max(p.r_i.norm(), p.r_j.norm()) <= c) keep.push_back(k);
    }
    if (keep.size() == X.size()) {
      if (lm.converged) break;
      why << "no convergence within " << opt.max_iterations
          << " iterations (last relative cost decrease " << lm.last_relative_decrease << ")";
      return fail(out, why.str());
    }
    out.rejected_outliers += static_cast<int>(X.size() - keep.size());
    if (round + 1 >= kRounds || out.rejected_outliers > opt.max_fraction_outliers * n_front ||
        static_cast<int>(keep.size()) < opt.min_points) {
      why << out.rejected_outliers << " of " << n_front << " matches rejected as outliers ("
          << keep.size() << " left after " << round + 1 << " rounds)";
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
  const std::size_t n = X.size();

  // Marginal covariance of z: inverse of the undamped Schur complement at the solution.
  Mat5 S;
  Vec5 b;
  std::vector<Eigen::Matrix3d> C_inv;
  if (!schur(ne, 0.0, S, b, C_inv)) return fail(out, "a point's information is singular");
  const Eigen::SelfAdjointEigenSolver<Mat5> eig(S);
  const double ev_min = eig.eigenvalues()[0], ev_max = eig.eigenvalues()[4];
  if (!(ev_min > opt.min_rcond * ev_max)) {
    why << "information of z is singular (eigenvalues " << ev_min << " .. " << ev_max
        << "): baseline direction or rotation unobservable";
    return fail(out, why.str());
  }
  out.covariance = eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() *
                   eig.eigenvectors().transpose();

  const PoseTerms pose(z);
  out.z = z;
  out.R_i_j = pose.R_j_i.transpose();
  out.t_i_j_unit = pose.t;
  std::vector<double> parallax(n);
  out.points_i = X;
  out.depths_i.resize(n);
  out.depths_j.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    out.depths_i[k] = X[k].z();
    out.depths_j[k] = (pose.R_j_i * (X[k] - pose.t)).z();
    const Eigen::Vector3d a = X[k], bb = X[k] - pose.t;
    parallax[k] = std::atan2(a.cross(bb).norm(), a.dot(bb)) * 180.0 / std::numbers::pi;
  }
  out.reprojection_rms_px =
      opt.pixel_sigma_px *
      std::sqrt(two_view_residuals(z, X, ui, uj, cam, opt.pixel_sigma_px).squaredNorm() /
                static_cast<double>(4 * n));
  out.median_parallax_deg = median(parallax);
  if (!(out.median_parallax_deg >= opt.min_parallax_deg)) {
    why << "median parallax " << out.median_parallax_deg << " deg below " << opt.min_parallax_deg
        << " deg (pure rotation or baseline too short for the scene)";
    return fail(out, why.str());
  }
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
