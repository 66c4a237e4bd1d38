// Kernels of the two-view refinement problem (two_view_problem.h): residuals and Jacobians of
// inverse-depth points, normal equations with Huber IRLS weights, Schur complement, sparse
// Levenberg-Marquardt.

#include "two_view_problem.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "nav/core/geometry/rotation.h"
#include "nav/vision/relative_pose_5dof.h"

namespace nav::vision::two_view {
namespace {

/// Projection in pixels and its Jacobian with respect to the camera-frame point.
Eigen::Vector2d project(const CameraIntrinsics& c, const Eigen::Vector3d& X, Mat23* J) {
  const double iz = 1.0 / X.z();
  if (J != nullptr) {
    *J << c.fx_px * iz, 0.0, -c.fx_px * X.x() * iz * iz,  //
        0.0, c.fy_px * iz, -c.fy_px * X.y() * iz * iz;
  }
  return {c.fx_px * X.x() * iz + c.cx_px, c.fy_px * X.y() * iz + c.cy_px};
}

/// Huber: rho(s) for s = |r|^2 of one 2-vector observation, and the IRLS weight rho'(s).
double huber_rho(double s, double c) { return s <= c * c ? s : 2.0 * c * std::sqrt(s) - c * c; }
double huber_weight(double s, double c) { return s <= c * c ? 1.0 : c / std::sqrt(s); }

NormalEquations build(const PoseState& x, const std::vector<Eigen::Vector3d>& X,
                      const std::vector<Eigen::Vector2d>& u_i,
                      const std::vector<Eigen::Vector2d>& u_j, const CameraIntrinsics& cam,
                      double inv_sigma, double huber_c) {
  const PoseTerms pose(x);
  NormalEquations ne;
  ne.H_kk.resize(X.size());
  ne.H_zk.resize(X.size());
  ne.g_k.resize(X.size());
  for (std::size_t k = 0; k < X.size(); ++k) {
    const PointResidual p = point_residual(pose, cam, X[k], u_i[k], u_j[k], inv_sigma, true);
    const double s_i = p.r_i.squaredNorm(), s_j = p.r_j.squaredNorm();
    const double w_i = huber_weight(s_i, huber_c), w_j = huber_weight(s_j, huber_c);
    ne.cost += huber_rho(s_i, huber_c) + huber_rho(s_j, huber_c);
    ne.H_kk[k] = w_i * p.J_i_p.transpose() * p.J_i_p + w_j * p.J_j_p.transpose() * p.J_j_p;
    ne.g_k[k] = w_i * p.J_i_p.transpose() * p.r_i + w_j * p.J_j_p.transpose() * p.r_j;
    ne.H_zk[k] = w_j * p.J_j_z.transpose() * p.J_j_p;
    ne.H_zz += w_j * p.J_j_z.transpose() * p.J_j_z;
    ne.g_z += w_j * p.J_j_z.transpose() * p.r_j;
  }
  return ne;
}

double robust_cost(const PoseState& x, const std::vector<Eigen::Vector3d>& X,
                   const std::vector<Eigen::Vector2d>& u_i, const std::vector<Eigen::Vector2d>& u_j,
                   const CameraIntrinsics& cam, double inv_sigma, double huber_c) {
  const PoseTerms pose(x);
  double cost = 0.0;
  for (std::size_t k = 0; k < X.size(); ++k) {
    const PointResidual p = point_residual(pose, cam, X[k], u_i[k], u_j[k], inv_sigma, false);
    cost += huber_rho(p.r_i.squaredNorm(), huber_c) + huber_rho(p.r_j.squaredNorm(), huber_c);
  }
  return cost;
}

/// A few Gauss-Newton steps on each point alone at fixed pose (each point's cost only goes
/// down). Interleaved with the joint steps this follows the long curved valley of weak
/// baselines, where the inverse depths and the baseline direction trade off, in far fewer
/// iterations (as in variable projection, the points are kept near their optimum).
void refine_points(const PoseState& x, std::vector<Eigen::Vector3d>& X,
                   const std::vector<Eigen::Vector2d>& ui, const std::vector<Eigen::Vector2d>& uj,
                   const CameraIntrinsics& cam, double inv_sigma, double c) {
  const PoseTerms pose(x);
  for (std::size_t k = 0; k < X.size(); ++k) {
    for (int it = 0; it < 2; ++it) {
      const PointResidual p = point_residual(pose, cam, X[k], ui[k], uj[k], inv_sigma, true);
      const double s_i = p.r_i.squaredNorm(), s_j = p.r_j.squaredNorm();
      const double w_i = huber_weight(s_i, c), w_j = huber_weight(s_j, c);
      const Eigen::Matrix3d H =
          w_i * p.J_i_p.transpose() * p.J_i_p + w_j * p.J_j_p.transpose() * p.J_j_p;
      const Eigen::Vector3d g =
          w_i * p.J_i_p.transpose() * p.r_i + w_j * p.J_j_p.transpose() * p.r_j;
      Eigen::Matrix3d H_inv;
      bool invertible = false;
      H.computeInverseWithCheck(H_inv, invertible, 1e-300);
      if (!invertible) break;
      const Eigen::Vector3d candidate = X[k] - H_inv * g;
      const PointResidual q = point_residual(pose, cam, candidate, ui[k], uj[k], inv_sigma, false);
      const double before = huber_rho(s_i, c) + huber_rho(s_j, c);
      const double after = huber_rho(q.r_i.squaredNorm(), c) + huber_rho(q.r_j.squaredNorm(), c);
      if (!(after < before)) break;
      X[k] = candidate;
    }
  }
}

}  // namespace

Mat3x2 tangent_basis(const Eigen::Vector3d& t) {
  const Eigen::Vector3d a =
      std::abs(t.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d b1 = (a - a.dot(t) * t).normalized();
  Mat3x2 B;
  B << b1, t.cross(b1);
  return B;
}

PoseState pose_from_z(const Vec5& z) { return {z.tail<3>(), baseline_direction(z[0], z[1])}; }

PoseState retract(const PoseState& x, const Vec5& delta) {
  PoseState out;
  out.t = (x.t + tangent_basis(x.t) * delta.head<2>()).normalized();
  for (int a = 0; a < 3; ++a) out.rpy[a] = core::wrap_angle(x.rpy[a] + delta[2 + a]);
  return out;
}

PoseTerms::PoseTerms(const PoseState& x) {
  R_j_i = core::rotation_from_euler(x.rpy).transpose();
  dR_j_i[0] = core::dR_droll(x.rpy).transpose();
  dR_j_i[1] = core::dR_dpitch(x.rpy).transpose();
  dR_j_i[2] = core::dR_dheading(x.rpy).transpose();
  t = x.t;
  B = tangent_basis(x.t);
}

Eigen::Vector3d to_inverse_depth(const Eigen::Vector3d& X) {
  return {X.x() / X.z(), X.y() / X.z(), 1.0 / X.z()};
}

Eigen::Vector3d from_inverse_depth(const Eigen::Vector3d& p) {
  return Eigen::Vector3d(p.x(), p.y(), 1.0) / p.z();
}

PointResidual point_residual(const PoseTerms& pose, const CameraIntrinsics& cam,
                             const Eigen::Vector3d& p, const Eigen::Vector2d& u_i,
                             const Eigen::Vector2d& u_j, double inv_sigma, bool jacobians) {
  PointResidual out;
  const Eigen::Vector3d m(p.x(), p.y(), 1.0);
  const Eigen::Vector3d w = m - p.z() * pose.t;
  const Eigen::Vector3d X_j = pose.R_j_i * w;  // camera j, up to the positive scale 1/rho
  Mat23 Jp_j;
  out.r_i = Eigen::Vector2d(cam.fx_px * p.x() + cam.cx_px - u_i.x(),
                            cam.fy_px * p.y() + cam.cy_px - u_i.y()) *
            inv_sigma;
  out.r_j = (project(cam, X_j, &Jp_j) - u_j) * inv_sigma;
  if (jacobians) {
    out.J_i_p << cam.fx_px * inv_sigma, 0.0, 0.0, 0.0, cam.fy_px * inv_sigma, 0.0;
    Eigen::Matrix3d dw_dp = Eigen::Matrix3d::Zero();
    dw_dp(0, 0) = 1.0;
    dw_dp(1, 1) = 1.0;
    dw_dp.col(2) = -pose.t;
    out.J_j_p = Jp_j * pose.R_j_i * dw_dp * inv_sigma;
    Eigen::Matrix<double, 3, 5> dXj_dz;
    dXj_dz.leftCols<2>() = -p.z() * pose.R_j_i * pose.B;
    for (int a = 0; a < 3; ++a) dXj_dz.col(2 + a) = pose.dR_j_i[a] * w;
    out.J_j_z = Jp_j * dXj_dz * inv_sigma;
  }
  return out;
}

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

std::vector<PointInformation> point_information(const PoseState& x,
                                                const std::vector<Eigen::Vector3d>& X,
                                                const std::vector<Eigen::Vector2d>& u_i,
                                                const std::vector<Eigen::Vector2d>& u_j,
                                                const CameraIntrinsics& cam, double inv_sigma) {
  const PoseTerms pose(x);
  std::vector<PointInformation> out(X.size());
  for (std::size_t k = 0; k < X.size(); ++k) {
    const PointResidual p = point_residual(pose, cam, X[k], u_i[k], u_j[k], inv_sigma, true);
    Eigen::Matrix<double, 4, 3> J_p;
    J_p << p.J_i_p, p.J_j_p;
    // q: the residual direction the point's own 3 unknowns cannot absorb.
    const Eigen::JacobiSVD<Eigen::Matrix<double, 4, 3>> svd(J_p, Eigen::ComputeFullU);
    out[k].q = svd.matrixU().col(3);
    out[k].a = p.J_j_z.transpose() * out[k].q.tail<2>();
  }
  return out;
}

namespace {

/// (I - H)^-1 for H = A^T C A, whose eigenvalues lie in [0, 1]: 1 where the matches of A's
/// columns alone decide a direction of the pose (no redundancy, an infinite detection limit),
/// clamped there to 1 - 1e-9 so that the bound stays finite.
Eigen::MatrixXd redundancy_inverse(const Eigen::MatrixXd& A, const Mat5& C) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A.transpose() * C * A);
  const Eigen::VectorXd inv = (1.0 - eig.eigenvalues().array()).max(1e-9).inverse().matrix();
  return eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose();
}

/// Mahalanobis size of the pose shift that blunders in A's matches at their detection limit
/// cause, per unit delta0^2: the largest eigenvalue of (I - H)^-1 H, i.e. of lambda / (1 - lambda)
/// over H's eigenvalues lambda (clamped as in redundancy_inverse).
double group_shift(const Eigen::MatrixXd& A, const Mat5& C) {
  const Eigen::ArrayXd lambda =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A.transpose() * C * A, Eigen::EigenvaluesOnly)
          .eigenvalues()
          .array();
  return (lambda / (1.0 - lambda).max(1e-9)).maxCoeff();
}

Eigen::MatrixXd columns(const std::vector<PointInformation>& a,
                        const std::vector<std::size_t>& group) {
  Eigen::MatrixXd A(5, static_cast<Eigen::Index>(group.size()));
  for (std::size_t g = 0; g < group.size(); ++g)
    A.col(static_cast<Eigen::Index>(g)) = a[group[g]].a;
  return A;
}

}  // namespace

ReliabilityBound reliability_bound(const std::vector<PointInformation>& a, const Mat5& C,
                                   double delta0, int max_group) {
  ReliabilityBound out;
  for (const PointInformation& p : a)
    out.max_leverage = std::max(out.max_leverage, p.a.dot(C * p.a));
  if (!(delta0 > 0.0)) return out;
  double size = 0.0;
  while (static_cast<int>(out.group.size()) < max_group && out.group.size() < a.size()) {
    std::vector<std::size_t> trial = out.group;
    trial.push_back(0);
    std::size_t best = a.size();
    for (std::size_t k = 0; k < a.size(); ++k) {
      if (std::find(out.group.begin(), out.group.end(), k) != out.group.end()) continue;
      trial.back() = k;
      const double s = group_shift(columns(a, trial), C);
      if (s > size) {
        size = s;
        best = k;
      }
    }
    if (best == a.size()) break;
    out.group.push_back(best);
  }
  if (out.group.empty()) return out;
  const Eigen::MatrixXd A = columns(a, out.group);
  const Eigen::MatrixXd CA = C * A;
  out.covariance = delta0 * delta0 * CA * redundancy_inverse(A, C) * CA.transpose();
  return out;
}

LmOutcome levenberg_marquardt(PoseState& x, std::vector<Eigen::Vector3d>& X,
                              const std::vector<Eigen::Vector2d>& ui,
                              const std::vector<Eigen::Vector2d>& uj, const CameraIntrinsics& cam,
                              double inv_sigma, double c, const TwoViewRefinementOptions& opt,
                              NormalEquations& ne) {
  LmOutcome out;
  const std::size_t n = X.size();
  double lambda = 1e-4;
  ne = build(x, X, ui, uj, cam, inv_sigma, c);
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
    const PoseState x_new = retract(x, dz);
    const double cost_new = robust_cost(x_new, X_new, ui, uj, cam, inv_sigma, c);
    if (std::isfinite(cost_new) && cost_new <= ne.cost) {
      out.last_relative_decrease = (ne.cost - cost_new) / std::max(ne.cost, 1e-300);
      x = x_new;
      X = std::move(X_new);
      refine_points(x, X, ui, uj, cam, inv_sigma, c);
      ne = build(x, X, ui, uj, cam, inv_sigma, c);
      lambda = std::max(lambda / 10.0, 1e-12);
      // Pose step in standard deviations (S-norm): stops once the pose no longer moves even if
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

Eigen::VectorXd stacked_residuals(const PoseState& x, const std::vector<Eigen::Vector3d>& p,
                                  const std::vector<Eigen::Vector2d>& u_i,
                                  const std::vector<Eigen::Vector2d>& u_j,
                                  const CameraIntrinsics& cam, double inv_sigma) {
  const PoseTerms pose(x);
  Eigen::VectorXd r(4 * static_cast<Eigen::Index>(p.size()));
  for (std::size_t k = 0; k < p.size(); ++k) {
    const PointResidual e = point_residual(pose, cam, p[k], u_i[k], u_j[k], inv_sigma, false);
    r.segment<2>(4 * static_cast<Eigen::Index>(k)) = e.r_i;
    r.segment<2>(4 * static_cast<Eigen::Index>(k) + 2) = e.r_j;
  }
  return r;
}

}  // namespace nav::vision::two_view
