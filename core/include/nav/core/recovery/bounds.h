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
// Truncated CG breaks the premise (Σ^ may be smaller than Σ); certify_truncation restores it
// from the TRUE residual R = E_r - Λ X of the recovered column X = Σ^_{*r} (n x d). The error
// E = Σ_{*r} - X = Σ R; with W = B_rr >= Σ_rr and B_ii >= Σ_ii, for the rows E_i of block i
//   ‖B_ii^-½ E_i W^-½‖₂ <= ‖Σ^½ R W^-½‖₂ =: κ̄,   κ̄² = λmax(W^-½ Rᵀ Σ R W^-½),
// bounded without Λ⁻¹ by K1, K2 or K3 (certificate.h); κ = the square root of the smallest: a
// factor on the blocks themselves, no m² added to rad². The certified joint of r <-> i is
//   J~ = [sym(X_rr) + 2κ W,  X_irᵀ ;  X_ir,  (1 + κ) Σ~_ii]  >=  J  (PSD difference),
// whatever the residual (derivation: docs/consistency.md "The certificate"); the robot bound
// becomes sym(X_rr) + κ W when that has smaller trace. κ, W, L and the B_jj are frozen at
// set_recovery: a bound tightened by a link of this snapshot is not a bound of its Σ; a state
// linked twice within one snapshot is proposed from its snapshot bound again and keeps the
// smaller-trace result. B_rr follows predictions (F B Fᵀ + Q).
// Exact refresh (refresh_exact): the ESDF's Λ only gains PSD terms (augmentation keeps every
// delayed state's marginal, updates add Hᵀ R⁻¹ H), so an exact marginal Σ_ii(t) (selected
// inversion) plus a rounding margin bounds Σ_ii for all later t, up to the rounding that later
// predictions store in Λ (predict_robot); Algorithm 1 tightens from it.
// Correlation-free fallback: for PSD [A B; Bᵀ C] and ω in (0, 1), [A B; Bᵀ C] <=
// blkdiag(A/ω, C/(1-ω)) (covariance intersection); update() also updates blkdiag(B_rr/ω,
// Σ~_ii/(1-ω)) for a few ω and keeps the smallest-trace posterior (all are certified).
// GUARANTEE (certify_truncation): if every state has a bound (insert() on every augmentation),
// the robot's prior bound is >= its covariance and the residual handed to set_recovery is the
// true one (or ρ >= its spectral norm), every Σ~_ii - Σ_ii is PSD up to rounding, whatever the
// CG budget. Without it: the paper's Algorithm 1 (κ = 0), conservative for exact recovery only.
// Costs: O(d³) per call, except set_recovery with the residual matrix (K2) and refresh_exact:
// O(n d³), once per image. Not thread-safe.

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "nav/core/recovery/certificate.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/status.h"

namespace nav::core {

struct BoundsOptions {
  /// Inflate by the certified error of a truncated recovery (see the file comment). false =
  /// the paper's uninflated Algorithm 1 (for measuring what truncation does to it).
  bool certify_truncation = true;
  /// τ, the relative rounding of quantities solved with Λ (κ(Λ) ≈ 1e14 on pose graphs):
  /// refresh_exact stores (1 + τ) Σ + τ diag(Σ) over the selected inverse Σ, and κ >= τ when
  /// certifying, as the computed residual cannot see the solve's rounding (1e-8 measured too
  /// small for both: docs/consistency.md "Exact refresh", "The certificate").
  double rounding_margin = 1e-6;
  /// Certify with K3 (certificate.h) when the recovery has a factor; false: K1/K2 only (the
  /// comparison of docs/consistency.md). Read by the callers that compute its input.
  bool old_state_energy = true;
};

/// The joint used for a link proposal between the robot r and state i (paper eq. 6).
struct LinkProposal {
  int state = -1;         ///< i
  Eigen::MatrixXd joint;  ///< 2d x 2d [Σ_rr Σ_ri; Σ_ir Σ~_ii], certified (file comment)
  double kappa = 0;       ///< κ of the certified joint (0 when not certifying)
};

/// When an earlier Λ was taken (CovarianceBounds::snapshot()).
struct BoundsSnapshot {
  long epoch = 0;       ///< set_recovery calls before it
  double growth = 0.0;  ///< Σ log(1 + ρ) of the predictions before it
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
  /// Σ~_ii = Σ_rr). Then B_rr <- (1 + ρ)(F B_rr Fᵀ + Q), ρ the rounding of Λ's update, which
  /// every stored bound gets too at the next set_recovery (refresh_exact of Λ clears it).
  Status predict_robot(const Eigen::MatrixXd& F, const Eigen::MatrixXd& Q, bool keep_current,
                       int kept_state);
  /// A measurement of the robot alone, z = h(x_r) + v, v ~ N(0, R), H (m x d): Joseph-form Kalman
  /// update of B_rr. The filter's robot marginal after it is the update of its prior marginal,
  /// monotone in the prior: B_rr >= Σ_rr holds. kNotPositiveDefinite (unchanged) if HBHᵀ + R is
  /// not SPD. O(d³).
  Status update_robot(const Eigen::MatrixXd& H, const Eigen::MatrixXd& R);
  Status insert(int state);  ///< state i gets the robot's bound (augmentation, no prediction)
  /// Hands in the recovery of this snapshot: sym(Σ^_rr) and ρ >= ‖E_r - ΛX‖₂ of the covariance
  /// columns (column_residual_spectral, or the looser Frobenius norm): κ by (K1), RᵀR <= ρ² I.
  /// Every non-robot block of the filter's `num_states` must have a bound (kInvalidArgument: the
  /// certificate would be void). Computes κ and tightens B_rr (certifying) or sets it to Σ^_rr.
  Status set_recovery(const Eigen::MatrixXd& sigma_rr, double residual_frobenius, int num_states);
  /// Same with the true residual matrix R = E_r - ΛX (n x d, StateRecovery::column_residual()):
  /// κ by the smallest of K1, K2 and K3, whose input `old_states` (e.g. StateRecovery::
  /// old_state_energy, a solve) is called only when K1 and K2 are above the rounding margin.
  /// kInvalidArgument if its result does not fit (old_end > num_states, energy not d x d).
  Status set_recovery(const Eigen::MatrixXd& sigma_rr,
                      const Eigen::Ref<const Eigen::MatrixXd>& residual, int num_states,
                      const std::function<OldStateEnergy()>& old_states = {});
  double kappa() const { return kappa_; }  ///< κ of the last set_recovery (0: not certifying)

  /// Resets every bound (the robot's too) to the exact marginal of the current Λ plus the
  /// rounding margin (file comment). Call before set_recovery of the same Λ. kInvalidArgument
  /// if the marginals' blocks do not match the filter's `num_states` or a state has no bound.
  Status refresh_exact(const ExactMarginals& exact, int num_states);
  /// Of the current Λ, for refresh_exact: the epoch and Σ log(1 + ρ) of the predictions so far.
  BoundsSnapshot snapshot() const { return {epoch_, growth_total_}; }
  /// The same from the exact Σ_jj of an EARLIER Λ of this filter with m <= num_states blocks
  /// (block j in rows [j d, (j+1) d) of `marginals`, m d x d): resets states 1..m-1 only; later
  /// states and the robot keep their bounds. Valid as Λ only gained PSD terms since (file
  /// comment). With `since` (that Λ's snapshot()) the marginals first grow by the predictions'
  /// rounding since, and a state a link tightened since keeps the smaller-trace of the two.
  /// kInvalidArgument for a bad shape or a state without bound.
  Status refresh_exact(const Eigen::Ref<const Eigen::MatrixXd>& marginals, int num_states,
                       const BoundsSnapshot* since = nullptr);

  /// The joint for a proposal between the robot and state i, from the recovered cross
  /// covariance Σ^_ir (rows of block i of the robot column). kUnknownState if i has no bound.
  Status propose(int state, const Eigen::MatrixXd& sigma_ir, LinkProposal* proposal) const;
  /// Covariance of x_i[0:2] − x_r[0:2] under propose()'s joint for a Σ^_ir of top-left 2x2
  /// `sigma_ir_top_left` (rr + ii − ir − irᵀ, the same inflations and floating-point operations)
  /// without building the joint: a cheap test per link candidate. kUnknownState without bound.
  Status offset_covariance_2d(int state, const Eigen::Matrix2d& sigma_ir_top_left,
                              Eigen::Matrix2d* covariance) const;

  /// A registration z = h(x_r, x_i) + v, v ~ N(0, R), H = [H_r | H_i] (m x d each, as the filter
  /// update's): Joseph-form update of the proposal's joint P, K = P Hᵀ (H P Hᵀ + R)⁻¹, P+ = (I -
  /// K H) P (I - K H)ᵀ + K R Kᵀ, Σ~_ii <- sym(P+_ii); certifying, also of the correlation-free
  /// candidates (file comment), keeping the smallest trace for Σ~_ii and B_rr. kNotPositiveDefinite
  /// (unchanged) if no innovation covariance is SPD (only uncertified, from a stale recovery).
  Status update(const LinkProposal& proposal, const Eigen::MatrixXd& H_r,
                const Eigen::MatrixXd& H_i, const Eigen::MatrixXd& R);

  bool contains(int state) const;
  const Eigen::MatrixXd& bound(int state) const;  ///< Σ~_ii (state must be contained)
  const Eigen::MatrixXd& robot_bound() const { return robot_bound_; }  ///< the certified B_rr
  double lambda_max_sigma_bound() const;  ///< L = Σ_j λmax(B_jj) >= λmax(Σ), current bounds
  double certificate_lambda() const { return certificate_lambda_; }  ///< L of the certificate
  int num_bounds() const { return num_bounds_; }
  /// Both ways; reading replaces the bounds, each of a state 1..num_filter_blocks-1
  /// (core/serialization/map_serialization.h, section "BNDS").
  template <class Archive>
  void serialize(Archive& ar, int num_filter_blocks);

 private:
  struct Entry {
    bool present = false;
    Eigen::MatrixXd bound;
    double lambda_max = 0.0;
    Eigen::MatrixXd snapshot_bound;  // as it was at set_recovery() of epoch snapshot_epoch
    double snapshot_lambda_max = 0.0;
    long snapshot_epoch = -1;
    long stored_epoch = -1;  // epoch_ when store() last set the bound
  };
  void store(int state, const Eigen::MatrixXd& bound);
  void reset_to_exact(int state, const Eigen::MatrixXd& exact_marginal);  ///< + rounding margin
  void apply_pending_growth();  ///< every stored bound *= exp(pending_growth_)
  /// Joseph-form posterior of the 2d x 2d `joint`; false if S is not SPD or it is not finite.
  static bool joseph(const Eigen::MatrixXd& joint, const Eigen::MatrixXd& H,
                     const Eigen::MatrixXd& R, Eigen::MatrixXd* posterior);
  void set_robot_bound(const Eigen::MatrixXd& bound);
  double robot_lambda_max() const;  ///< λmax(B_rr): the cached value or, if none, computed
  /// R_0ᵀ W R_0 + Σ R_jᵀ B_jj R_j, j in [max(first, 1), last): K2, and K3's T part.
  Eigen::MatrixXd weighted_residual(const Eigen::Ref<const Eigen::MatrixXd>& R, int first, int last,
                                    const Eigen::MatrixXd& W) const;
  /// set_recovery's common part; kappa_squared(W) returns an upper bound of κ̄².
  Status set_recovery_with(const Eigen::MatrixXd& sigma_rr, double residual_frobenius,
                           int num_states,
                           const std::function<double(const Eigen::MatrixXd&)>& kappa_squared);

  int block_dim_;
  BoundsOptions options_;
  std::vector<Entry> entries_;
  int num_bounds_ = 0;
  double lambda_sum_ = 0.0;
  Eigen::MatrixXd robot_bound_;
  double robot_lambda_max_ = 0.0;  // an upper bound of λmax(robot_bound_); < 0: none cached
  Eigen::MatrixXd sigma_rr_hat_;
  double residual_frobenius_ = 0.0;
  double kappa_ = 0.0;
  Eigen::MatrixXd certificate_robot_bound_;  // W: the robot bound frozen at set_recovery
  double certificate_lambda_ = 0.0;          // L frozen at set_recovery
  long epoch_ = 0;                           // incremented by set_recovery
  double pending_growth_ = 0.0;              // Σ log(1 + ρ) of the predictions since set_recovery
  double growth_total_ = 0.0;                // Σ log(1 + ρ) of every prediction
};

}  // namespace nav::core
