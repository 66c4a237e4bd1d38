#pragma once
// Conservative covariance bounds for data association: Algorithm 1 of Eustice et al., "Visually
// Navigating the RMS Titanic with SLAM Information Filters" (RSS 2005, sec. III-B), made
// conservative under the truncated (fixed-budget) CG recovery of state_recovery.h.
//
// Algorithm 1 (paper):
//   * on inserting delayed state i store Σ~_ii = Σ_rr (the robot's covariance at that time);
//   * link proposal r <-> i uses the joint  [Σ_rr Σ_ri; Σ_ir Σ~_ii]  (paper eq. 6), from which the
//     first-order relative pose x_ri = (-)x_r (+) x_i and its covariance follow;
//   * on a successful registration z_ri, a constant-time Kalman update of that joint gives the
//     tightened Σ~_ii+ (only that block is kept). Bounds never feed the filter.
// Why it is conservative with an exact recovery: Σ~_ii >= Σ_ii (induction) makes the joint
// above >= the true joint of (r, i); a Kalman (Joseph-form) update is monotone in the prior, and
// the filter's own marginal of i after the same measurement equals the update of the true joint,
// later information only shrinks it. Everything here is in the filter's linearisation.
//
// Truncated CG breaks the premise: Σ^ (the CG estimate) may be smaller than Σ. We make the
// bounds certified again from the TRUE residual of the recovered column (certify_truncation):
//   X = Σ^_{*r} (n x d), R = E_r - Λ X, error E = Σ_{*r} - X = Λ⁻¹ R. For the rows of block j,
//     ‖E_j‖₂ = ‖S_jᵀ Λ^{-1/2} · Λ^{-1/2} R‖₂ <= sqrt(λmax(Σ_jj)) · sqrt(λmax(Σ)) · ‖R‖₂
//   (‖S_jᵀΛ^{-1/2}‖₂² = λmax(S_jᵀΛ⁻¹S_j) = λmax(Σ_jj), ‖Λ^{-1/2}R‖₂² <= λmax(Λ⁻¹)‖R‖₂²).
//   λmax(Σ) needs no eigen-solve of Λ: for PSD Σ, λmax(Σ) <= Σ_j λmax(Σ_jj) (Cauchy-Schwarz on
//   vᵀΣv = ‖Σ_j Σ^{1/2}S_j v_j‖²), and Σ_jj <= B_jj for our stored bounds B (the robot included).
//   Hence, with L = Σ_j λmax(B_jj) and ρ any upper bound of the spectral norm ‖R‖₂ (the
//   recovery reports ‖R‖₂ itself, RecoveryResult::column_residual_spectral; the Frobenius norm
//   ‖R‖_F >= ‖R‖₂ is also valid, up to sqrt(d) looser),
//     ε_j = sqrt(λmax(B_jj) · L) · ρ   bounds ‖E_j‖₂ for every block j.               (C1)
//   Inflated joint for a proposal r <-> i:
//     J~ = [sym(X_rr) + (ε_r + ε_i) I,  X_irᵀ ;  X_ir,  Σ~_ii + ε_i I].
//   J~ - J = [ε_r I - E_rr, 0; 0, 0] + [ε_i I, -E_irᵀ; -E_ir, ε_i I] + [0 0; 0 Σ~_ii - Σ_ii],
//   each term PSD (‖E_rr‖ <= ε_r, ‖E_ir‖ <= ε_i, induction), so J~ >= J and the argument above
//   holds again. At insertion Σ~_ii = sym(X_rr) + ε_r I >= Σ_rr.
//   L and every B_jj used in (C1) are frozen when the snapshot's recovery is handed in
//   (set_recovery): a bound tightened by a link of this snapshot is not yet a bound of the
//   snapshot's Σ. A state linked twice within one snapshot is proposed from its snapshot bound
//   again and keeps the smaller-trace of the two (both are valid after both links).
//   The robot bound B_rr is propagated through predictions (F B Fᵀ + Q, valid because
//   Σ_rr' = F Σ_rr Fᵀ + Q) and replaced by sym(X_rr) + ε_r I whenever that has smaller trace.
// Correlation-free fallback (certify_truncation only): (C1) is a worst-case bound that grows
//   with the map (L sums over all states), so after a short CG budget the inflated joint can be
//   far looser than needed. For any ω in (0, 1) and PSD [A B; Bᵀ C],
//     [A B; Bᵀ C] <= blkdiag(A/ω, C/(1-ω))                 (covariance intersection)
//   so blkdiag(B_rr/ω, Σ~_ii/(1-ω)) also bounds the true joint using only stored bounds. update()
//   runs the Kalman update on the certified CG joint and on this joint for a few ω, and keeps
//   the posterior block of smallest trace for Σ~_ii and for the robot bound B_rr (every
//   candidate is >= the true posterior, so any choice is certified). Sequential links within a
//   snapshot are fine: the fallback uses the current bounds, which hold after earlier links.
// Measured limit (parking-garage, README): with a fixed budget of 5-40 PCG iterations the
//   block-Jacobi PCG residual stays O(‖E_r‖) (relative residual 17-30) on this badly
//   conditioned Λ, so ε_j exceeds the bounds themselves and every stored bound comes from the
//   correlation-free fallback above; an exact recovery (--direct) gives log-det ratios of
//   median 12.8 instead of 17.3. Tighter bounds under truncation need a faster-converging
//   recovery (a better preconditioner), not a sharper form of (C1).
// GUARANTEE (certify_truncation = true): if every state of the filter has a bound (insert() on
// every augmentation), the prior bound of the robot is >= its covariance, and the residual norm
// passed to set_recovery() is >= the true ‖E_r - Λ X‖₂ of the column handed to propose(), then
// every stored Σ~_ii satisfies Σ~_ii - Σ_ii >= 0 up to rounding, whatever the CG budget. A large
// residual makes the bounds loose, never over-confident. With certify_truncation = false this is
// the paper's Algorithm 1 as published (ε = 0), conservative only for an exact recovery.
//
// Costs: every call is O(block_dim³) and independent of the map size (λmax of one block by a
// self-adjoint eigen-solve, L kept as a running sum). Not thread-safe (recovery thread).

#include <Eigen/Core>

#include <vector>

#include "nav/core/status.h"

namespace nav::core {

struct BoundsOptions {
  /// Inflate by the certified error of a truncated recovery (see the file comment). false =
  /// the paper's uninflated Algorithm 1 (for measuring what truncation does to it).
  bool certify_truncation = true;
};

/// The joint used for a link proposal between the robot r and state i (paper eq. 6).
struct LinkProposal {
  int state = -1;            ///< i
  Eigen::MatrixXd joint;     ///< 2d x 2d [Σ_rr Σ_ri; Σ_ir Σ~_ii], inflated when certifying
  double epsilon_robot = 0;  ///< ε_r used (0 when not certifying)
  double epsilon_state = 0;  ///< ε_i used
};

class CovarianceBounds {
 public:
  explicit CovarianceBounds(int block_dim, BoundsOptions options = {});

  int block_dim() const { return block_dim_; }
  const BoundsOptions& options() const { return options_; }

  /// The robot's prior covariance P0 (an upper bound of Σ_rr by definition).
  Status initialize_robot(const Eigen::MatrixXd& P0);

  /// The filter predicted x_{t+1} = f(x_t) + w with Jacobian F and noise Q. When keep_current,
  /// the old robot became delayed state `kept_state` and gets the robot's bound (Algorithm 1:
  /// Σ~_ii = Σ_rr). Then B_rr <- F B_rr Fᵀ + Q.
  Status predict_robot(const Eigen::MatrixXd& F, const Eigen::MatrixXd& Q, bool keep_current,
                       int kept_state);

  /// A measurement of the robot alone, z = h(x_r) + v, v ~ N(0, R), linearised with H (m x d):
  /// Joseph-form Kalman update of the robot bound. The filter's robot marginal after a unary
  /// update is exactly the Kalman update of its prior marginal, and the update is monotone in the
  /// prior, so B_rr >= Σ_rr still holds afterwards. Keeps B_rr (and with it every new state's
  /// bound and L) from growing like an unaided prediction between recoveries. O(d³).
  /// kNotPositiveDefinite (bound unchanged) if H B Hᵀ + R is not SPD.
  Status update_robot(const Eigen::MatrixXd& H, const Eigen::MatrixXd& R);

  /// Inserts delayed state i with the robot's current bound (an augmentation without prediction).
  Status insert(int state);

  /// Hands in the recovery of this snapshot: sym(Σ^_rr) and an upper bound of the true
  /// residual's spectral norm ‖E_r - ΛX‖₂ of the covariance columns (column_residual_spectral;
  /// the Frobenius norm is valid too, looser). The parameter name is historical.
  /// `num_states` is the filter's number of blocks: every non-robot block must have a bound (kInvalidArgument otherwise: the certificate would be void).
  /// Computes ε_r and tightens the robot bound (certifying) or sets it to Σ^_rr (not certifying).
  Status set_recovery(const Eigen::MatrixXd& sigma_rr, double residual_frobenius, int num_states);

  /// Certified error radius ε_j of the recovered rows of a block whose covariance is bounded
  /// by a matrix with largest eigenvalue lambda_max_block (formula C1); 0 when not certifying.
  double epsilon(double lambda_max_block) const;

  /// The joint for a proposal between the robot and state i, from the recovered cross
  /// covariance Σ^_ir (rows of block i of the robot column). kUnknownState if i has no bound.
  Status propose(int state, const Eigen::MatrixXd& sigma_ir, LinkProposal* proposal) const;

  /// Covariance of the offset of the first two elements, x_i[0:2] − x_r[0:2], under the joint
  /// propose() would build from a Σ^_ir whose top-left 2x2 is `sigma_ir_top_left` (rr + ii − ir
  /// − irᵀ, same inflations, same floating-point operations: equal to computing it from
  /// propose()'s joint), without building the 2d x 2d joint: a cheap test per link candidate.
  /// kUnknownState if i has no bound.
  Status offset_covariance_2d(int state, const Eigen::Matrix2d& sigma_ir_top_left,
                              Eigen::Matrix2d* covariance) const;

  /// A successful registration z = h(x_r, x_i) + v, v ~ N(0, R), linearised with
  /// H = [H_r | H_i] (m x d each): Joseph-form Kalman update of the proposal's joint,
  ///   K = P Hᵀ (H P Hᵀ + R)⁻¹,  P+ = (I - K H) P (I - K H)ᵀ + K R Kᵀ,
  /// and Σ~_ii <- sym(P+_ii). Use the same H and R as the filter update. When certifying, the
  /// correlation-free candidates (file comment) are updated too and the smallest-trace
  /// posterior kept, for Σ~_ii and for the robot bound. kNotPositiveDefinite if no candidate's
  /// innovation covariance is SPD (possible only without certification, from a stale
  /// recovery): the bound is then left unchanged.
  Status update(const LinkProposal& proposal, const Eigen::MatrixXd& H_r,
                const Eigen::MatrixXd& H_i, const Eigen::MatrixXd& R);

  bool contains(int state) const;
  /// Σ~_ii (state must be contained).
  const Eigen::MatrixXd& bound(int state) const;
  /// Current certified bound of the robot covariance.
  const Eigen::MatrixXd& robot_bound() const { return robot_bound_; }
  /// L = Σ_j λmax(B_jj) >= λmax(Σ) of the current bounds (valid while the bounds are).
  double lambda_max_sigma_bound() const { return lambda_sum_ + robot_lambda_max_; }
  /// L frozen at the last set_recovery (the one the certificate uses).
  double certificate_lambda() const { return certificate_lambda_; }
  int num_bounds() const { return num_bounds_; }
  /// Both ways; reading replaces the bounds and requires every bound to belong to a delayed
  /// state 1..num_filter_blocks-1 (core/serialization/map_serialization.h, section "BNDS").
  template <class Archive>
  void serialize(Archive& ar, int num_filter_blocks);

 private:
  struct Entry {
    bool present = false;
    Eigen::MatrixXd bound;
    double lambda_max = 0.0;
    // The bound as it was at set_recovery() of snapshot `snapshot_epoch` (see file comment).
    Eigen::MatrixXd snapshot_bound;
    double snapshot_lambda_max = 0.0;
    long snapshot_epoch = -1;
  };
  void store(int state, const Eigen::MatrixXd& bound);
  /// Joseph-form posterior of `joint` (2d x 2d); false if S is not SPD or the result not finite.
  static bool joseph(const Eigen::MatrixXd& joint, const Eigen::MatrixXd& H,
                     const Eigen::MatrixXd& R, Eigen::MatrixXd* posterior);
  void set_robot_bound(const Eigen::MatrixXd& bound);

  int block_dim_;
  BoundsOptions options_;
  std::vector<Entry> entries_;
  int num_bounds_ = 0;
  double lambda_sum_ = 0.0;
  Eigen::MatrixXd robot_bound_;
  double robot_lambda_max_ = 0.0;
  Eigen::MatrixXd sigma_rr_hat_;
  double residual_frobenius_ = 0.0;
  double epsilon_robot_ = 0.0;
  double certificate_lambda_ = 0.0;  // L frozen at set_recovery
  long epoch_ = 0;                   // incremented by set_recovery
};

/// λmax of a symmetric matrix (self-adjoint eigen-solve; for small blocks).
double lambda_max_symmetric(const Eigen::MatrixXd& m);

}  // namespace nav::core
