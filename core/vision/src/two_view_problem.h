#pragma once
// Private kernels of the two-view refinement (two_view_refinement.cpp; see
// two_view_refinement.h for the problem). Not installed, not part of nav_vision's interface.
//
// Points are in inverse depth in camera i, p = (alpha, beta, rho) = (x/z, y/z, 1/z) (Civera,
// Davison & Montiel, IEEE T-RO 24(5), 2008): camera i's projection is linear in p and camera
// j's is that of the homogeneous point R_i_j^T (m - rho t), m = (alpha, beta, 1), finite for
// distant points (rho -> 0) where a Euclidean X makes Gauss-Newton crawl along the depth.
// The marginal covariance of z does not depend on the points' parametrisation.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "nav/vision/relative_pose_5dof.h"
#include "nav/vision/two_view_refinement.h"
#include "nav/vision/vision_types.h"

namespace nav::vision::two_view {

using Mat23 = Eigen::Matrix<double, 2, 3>;
using Mat25 = Eigen::Matrix<double, 2, 5>;
using Mat53 = Eigen::Matrix<double, 5, 3>;

/// The pose while solving: Euler angles of R_i_j and the unit baseline t_i_j. Updated by a
/// 5-vector delta = [b (2); d_rpy (3)], t <- normalise(t + B b) with B an orthonormal basis of
/// t's tangent plane: unlike (azimuth, elevation) this has no singularity where the baseline
/// points along the optical axis (forward or vertical motion), where the solve would crawl.
struct PoseState {
  Eigen::Vector3d rpy = Eigen::Vector3d::Zero();
  Eigen::Vector3d t = Eigen::Vector3d::UnitX();
};

/// Orthonormal 3x2 basis of the plane orthogonal to the unit vector t.
Mat3x2 tangent_basis(const Eigen::Vector3d& t);
PoseState pose_from_z(const Vec5& z);
PoseState retract(const PoseState& x, const Vec5& delta);

/// Pose-dependent quantities shared by every point.
struct PoseTerms {
  Eigen::Matrix3d R_j_i;                  ///< R_i_j^T
  std::array<Eigen::Matrix3d, 3> dR_j_i;  ///< d(R_i_j^T) / d(roll, pitch, heading)
  Eigen::Vector3d t;                      ///< Unit baseline t_i_j.
  Mat3x2 B;                               ///< tangent_basis(t): d t / d b at b = 0.
  explicit PoseTerms(const PoseState& x);
};

Eigen::Vector3d to_inverse_depth(const Eigen::Vector3d& X);
Eigen::Vector3d from_inverse_depth(const Eigen::Vector3d& p);

/// Whitened residuals of one point in both images, with Jacobians when asked (with respect to
/// the inverse-depth point p and z).
struct PointResidual {
  Eigen::Vector2d r_i, r_j;
  Mat23 J_i_p, J_j_p;
  Mat25 J_j_z;
};

PointResidual point_residual(const PoseTerms& pose, const CameraIntrinsics& cam,
                             const Eigen::Vector3d& p, const Eigen::Vector2d& u_i,
                             const Eigen::Vector2d& u_j, double inv_sigma, bool jacobians);

/// Linear triangulation (Hartley & Zisserman 12.2) in camera i (Euclidean) from normalised
/// coordinates.
Eigen::Vector3d triangulate(const Eigen::Vector2d& x_i, const Eigen::Vector2d& x_j,
                            const Eigen::Matrix3d& R_j_i, const Eigen::Vector3d& t_i_j);

/// Normal equations of the (robust) whitened problem: pose block, point blocks, couplings.
struct NormalEquations {
  Mat5 H_zz = Mat5::Zero();
  Vec5 g_z = Vec5::Zero();
  std::vector<Eigen::Matrix3d> H_kk;
  std::vector<Mat53> H_zk;
  std::vector<Eigen::Vector3d> g_k;
  double cost = 0.0;  // sum of rho
};

/// Schur complement S = H_zz - sum H_zk H_kk^-1 H_kz (with damping lambda on every diagonal,
/// Marquardt scaling) and the reduced right-hand side; false when a point block is singular.
bool schur(const NormalEquations& ne, double lambda, Mat5& S, Vec5& b,
           std::vector<Eigen::Matrix3d>& H_kk_inv);

/// Each point's share of the undamped Schur complement at a solution with unit weights,
/// S = sum_k a_k a_k^T: its information on the pose once its own 3-D point is eliminated is
/// rank one (4 residuals, 3 point unknowns), a_k = J_z^T q_k with q_k the unit residual
/// direction orthogonal to the point Jacobian's columns. Its leverage h_k = a_k^T S^-1 a_k
/// (sum_k h_k = 5) is the hat-matrix diagonal of regression (Hoaglin & Welsch, Am. Stat.
/// 32(1), 1978): near 1, the point decides a direction of the pose alone. A whitened residual
/// perturbation dr_k moves the solution's pose by S^-1 sum_k a_k q_k^T dr_k (to first order).
struct PointInformation {
  Vec5 a;
  Eigen::Vector4d q;  ///< [image i (2); image j (2)], whitened residual space
};
std::vector<PointInformation> point_information(const PoseState& x,
                                                const std::vector<Eigen::Vector3d>& p,
                                                const std::vector<Eigen::Vector2d>& u_i,
                                                const std::vector<Eigen::Vector2d>& u_j,
                                                const CameraIntrinsics& cam, double inv_sigma);

/// Consider covariance (Schmidt; Bierman, "Factorization methods for discrete sequential
/// estimation", 1977, section VI.2) of the pose, in the solver's delta, for systematic feature
/// displacements: in each image a smooth field d(u) = Phi(u) b, Phi the quadratic monomials
/// 1, x, y, x^2, xy, y^2 per axis in the image's points centred on the principal point and
/// scaled by their largest offset along each axis, with independent coefficients of sigma_px each.
/// = sigma_px^2 C F F^T C, F = inv_sigma sum_k a_k q_k^T blockdiag(Phi(u_i,k), Phi(u_j,k)).
Mat5 systematic_field_covariance(const std::vector<PointInformation>& info,
                                 const std::vector<Eigen::Vector2d>& u_i,
                                 const std::vector<Eigen::Vector2d>& u_j,
                                 const CameraIntrinsics& cam, double inv_sigma, const Mat5& C,
                                 double sigma_px);

/// Baarda's external reliability (Foerstner, "Reliability analysis of parameter estimation in
/// linear models with applications to mensuration problems in computer vision", CVGIP 40(3),
/// 1987): blunders in a group G of matches, of joint non-centrality delta0 (at the limit the
/// residuals can detect), shift the pose by dz with dz dz^T <= delta0^2 C A_G (I - H_GG)^-1
/// A_G^T C, C = S^-1 the pose covariance, A_G the matches' columns a_k (point_information),
/// H_GG = A_G^T C A_G. G is grown greedily from the match of largest leverage up to max_group
/// matches, each time by the match that enlarges the shift's Mahalanobis size most: mismatches
/// that agree with each other mask one another, and one match's leverage does not show them.
struct ReliabilityBound {
  Mat5 covariance = Mat5::Zero();  ///< That bound, in the parameters of C; zero if delta0 <= 0.
  std::vector<std::size_t> group;  ///< G, indices into a.
  double max_leverage = 0.0;       ///< max_k a_k^T C a_k.
};
ReliabilityBound reliability_bound(const std::vector<PointInformation>& a, const Mat5& C,
                                   double delta0, int max_group);

/// Result of one Levenberg-Marquardt run.
struct LmOutcome {
  int iterations = 0;
  bool converged = false;
  double last_relative_decrease = 1.0;
  std::string error;  // non-empty: numerical failure
};

/// Sparse Levenberg-Marquardt (Hartley & Zisserman A6.3) from (x, p) with Huber kink c (in
/// sigmas); `ne` returns the normal equations (in delta, see PoseState) at the final (x, p).
LmOutcome levenberg_marquardt(PoseState& x, std::vector<Eigen::Vector3d>& p,
                              const std::vector<Eigen::Vector2d>& ui,
                              const std::vector<Eigen::Vector2d>& uj, const CameraIntrinsics& cam,
                              double inv_sigma, double c, const TwoViewRefinementOptions& opt,
                              NormalEquations& ne);

/// Whitened residuals [r_i; r_j] per point (no robust loss) of inverse-depth points.
Eigen::VectorXd stacked_residuals(const PoseState& x, const std::vector<Eigen::Vector3d>& p,
                                  const std::vector<Eigen::Vector2d>& u_i,
                                  const std::vector<Eigen::Vector2d>& u_j,
                                  const CameraIntrinsics& cam, double inv_sigma);

}  // namespace nav::vision::two_view
