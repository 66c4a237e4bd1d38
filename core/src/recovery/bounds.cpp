// Algorithm 1 of Eustice et al. (RSS 2005) with certified inflation (see recovery/bounds.h).
#include "nav/core/recovery/bounds.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace nav::core {
namespace {

Eigen::MatrixXd symmetric(const Eigen::MatrixXd& m) { return 0.5 * (m + m.transpose()); }

bool finite(const Eigen::MatrixXd& m) { return m.allFinite(); }

std::string shape(const Eigen::MatrixXd& m) {
  return std::to_string(m.rows()) + "x" + std::to_string(m.cols());
}

/// (1 + τ) S + τ diag|S| of a symmetric S: the rounding margin of a quantity computed with a
/// factor of Λ (exact refresh, K3 energy). Scaled by the diagonal (each variance in its own
/// unit): |Δ_kl| <= τ sqrt(S_kk S_ll) / d is covered, since d·diag(S) − Δ is diagonally
/// dominant after the diagonal scaling.
Eigen::MatrixXd padded(const Eigen::MatrixXd& sigma, double tau) {
  const Eigen::MatrixXd s = symmetric(sigma);
  Eigen::MatrixXd out = (1.0 + tau) * s;
  out.diagonal() += tau * s.diagonal().cwiseAbs();
  return out;
}

/// Relative rounding of the marginals that Λ holds after a prediction x_{t+1} = f(x_t) + w.
/// The information form adds FᵀQ⁻¹F to Λ_tt (esdf.cpp), and marginalising x_t cancels most of
/// it again in its neighbours' blocks (the robot's own block is formed without that difference,
/// esdf.cpp), so those blocks carry an absolute rounding of order ε‖FᵀQ⁻¹F‖ beside an
/// information of order B⁻¹. The marginals of the stored Λ then
/// differ from the recursion F B Fᵀ + Q by a relative ρ ≈ ε λmax(B^½ FᵀQ⁻¹F B^½) <=
/// ε tr(FᵀQ⁻¹F B) = ε tr(Q⁻¹ F B Fᵀ): 1e-7 to 1e-6 after the 5 ms steps that follow images on
/// the default dive (Q ∝ dt³ in position), where the exact marginals fell below the recursion by
/// 1.0 ρ (docs/consistency.md "Rounding of short predictions"). The perturbation δ of Λ has
/// λmax(Σ^½ δ Σ^½) <= ρ, so EVERY marginal, not only the robot's, may grow by a factor 1 + ρ:
/// stored bounds are grown by the product at the next set_recovery. Takes FBF = F B Fᵀ; returns
/// 8 ε tr(Q⁻¹ FBF), 0 if Q is not positive definite (the filter refuses such a prediction).
double prediction_rounding(const Eigen::MatrixXd& Q, const Eigen::MatrixXd& FBF) {
  constexpr double kSafety = 8.0;
  const Eigen::LLT<Eigen::MatrixXd> llt(symmetric(Q));
  if (llt.info() != Eigen::Success) return 0.0;
  const double trace = llt.solve(FBF).trace();
  return kSafety * std::numeric_limits<double>::epsilon() * std::max(0.0, trace);
}

}  // namespace

CovarianceBounds::CovarianceBounds(int block_dim, BoundsOptions options)
    : block_dim_(block_dim), options_(options) {
  if (block_dim < 1) {
    throw std::invalid_argument("CovarianceBounds: block_dim must be >= 1, got " +
                                std::to_string(block_dim));
  }
}

void CovarianceBounds::set_robot_bound(const Eigen::MatrixXd& bound) {
  robot_bound_ = symmetric(bound);
  robot_lambda_max_ = -1.0;  // set at every prediction, read once per image: computed then
}

double CovarianceBounds::robot_lambda_max() const {
  return robot_lambda_max_ >= 0.0 ? robot_lambda_max_
                                  : std::max(0.0, lambda_max_symmetric(robot_bound_));
}

double CovarianceBounds::lambda_max_sigma_bound() const { return lambda_sum_ + robot_lambda_max(); }

void CovarianceBounds::store(int state, const Eigen::MatrixXd& bound) {
  if (static_cast<size_t>(state) >= entries_.size()) {
    entries_.resize(std::max(static_cast<size_t>(state) + 1, entries_.size() * 3 / 2));
  }
  Entry& e = entries_[static_cast<size_t>(state)];
  Eigen::MatrixXd candidate = symmetric(bound);
  if (e.present) {
    if (e.snapshot_epoch == epoch_) {
      // Already tightened within this snapshot: both are valid, keep the smaller.
      if (candidate.trace() >= e.bound.trace()) return;
    } else {
      e.snapshot_bound = e.bound;
      e.snapshot_lambda_max = e.lambda_max;
      e.snapshot_epoch = epoch_;
    }
    lambda_sum_ -= e.lambda_max;
  } else {
    ++num_bounds_;
  }
  e.present = true;
  e.stored_epoch = epoch_;
  e.bound = std::move(candidate);
  e.lambda_max = std::max(0.0, lambda_max_symmetric(e.bound));
  lambda_sum_ += e.lambda_max;
}

Status CovarianceBounds::initialize_robot(const Eigen::MatrixXd& P0) {
  if (P0.rows() != block_dim_ || P0.cols() != block_dim_ || !finite(P0)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::initialize_robot: P0 must be finite " +
                             std::to_string(block_dim_) + "x" + std::to_string(block_dim_) +
                             ", got " + shape(P0));
  }
  entries_.clear();
  num_bounds_ = 0;
  epoch_ = 0;
  pending_growth_ = 0.0;
  growth_total_ = 0.0;
  certificate_lambda_ = 0.0;
  lambda_sum_ = 0.0;
  set_robot_bound(P0);
  sigma_rr_hat_ = robot_bound_;
  certificate_robot_bound_ = robot_bound_;
  residual_frobenius_ = 0.0;
  kappa_ = 0.0;
  return Status::Ok();
}

Status CovarianceBounds::predict_robot(const Eigen::MatrixXd& F, const Eigen::MatrixXd& Q,
                                       bool keep_current, int kept_state) {
  if (F.rows() != block_dim_ || F.cols() != block_dim_ || Q.rows() != block_dim_ ||
      Q.cols() != block_dim_ || !finite(F) || !finite(Q)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::predict_robot: F " + shape(F) + " and Q " +
                             shape(Q) + " must be finite and of block size " +
                             std::to_string(block_dim_));
  }
  if (robot_bound_.size() == 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::predict_robot: initialize_robot() first");
  }
  const Eigen::MatrixXd FBF = F * robot_bound_ * F.transpose();
  const double rounding = prediction_rounding(Q, FBF);
  if (keep_current) {
    if (kept_state < 1) return insert(kept_state);  // its error names the bad index
    store(kept_state, robot_bound_);  // grown with the others at the next set_recovery
  }
  set_robot_bound((1.0 + rounding) * (FBF + Q));
  pending_growth_ += std::log1p(rounding);
  growth_total_ += std::log1p(rounding);
  return Status::Ok();
}

void CovarianceBounds::apply_pending_growth() {
  if (pending_growth_ == 0.0) return;
  const double grow = std::exp(pending_growth_);
  pending_growth_ = 0.0;
  lambda_sum_ = 0.0;
  for (Entry& e : entries_) {
    if (!e.present) continue;
    e.bound *= grow;
    e.lambda_max *= grow;
    lambda_sum_ += e.lambda_max;
  }
}

Status CovarianceBounds::insert(int state) {
  if (state < 1) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::insert: delayed state index must be >= 1 (block 0 "
                         "is the robot), got " + std::to_string(state));
  }
  if (robot_bound_.size() == 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::insert: initialize_robot() first");
  }
  store(state, robot_bound_);
  return Status::Ok();
}

Status CovarianceBounds::set_recovery(const Eigen::MatrixXd& sigma_rr, double residual_frobenius,
                                      int num_states) {
  // (K1) with ‖R‖₂ <= ρ only: Rᵀ Σ R <= L ρ² I.
  const double rho_sq = residual_frobenius * residual_frobenius;
  return set_recovery_with(sigma_rr, residual_frobenius, num_states, [&](const Eigen::MatrixXd& W) {
    return certificate_lambda_ * rho_sq *
           lambda_max_scaled(Eigen::MatrixXd::Identity(block_dim_, block_dim_), W);
  });
}

Status CovarianceBounds::set_recovery(const Eigen::MatrixXd& sigma_rr,
                                      const Eigen::Ref<const Eigen::MatrixXd>& residual,
                                      int num_states,
                                      const std::function<OldStateEnergy()>& old_states) {
  const int d = block_dim_;
  if (residual.rows() != Eigen::Index{num_states} * d || residual.cols() != d ||
      !residual.allFinite()) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::set_recovery: residual is " +
                             std::to_string(residual.rows()) + "x" +
                             std::to_string(residual.cols()) + ", expected finite " +
                             std::to_string(num_states * d) + "x" + std::to_string(d));
  }
  const Eigen::MatrixXd gram = residual.transpose() * residual;
  const double spectral = std::sqrt(std::max(0.0, lambda_max_symmetric(gram)));
  Status energy_status = Status::Ok();
  const auto kappa_squared = [&](const Eigen::MatrixXd& W) {
    const Eigen::MatrixXd all = weighted_residual(residual, 0, num_states, W);
    const double k12 = std::min(certificate_lambda_ * lambda_max_scaled(gram, W),
                                num_states * lambda_max_scaled(all, W));
    const double floor = options_.rounding_margin * options_.rounding_margin;
    if (!old_states || k12 <= floor) return k12;
    const OldStateEnergy old = old_states();
    if (old.old_end == 0) return k12;
    if (old.old_end < 1 || old.old_end > num_states || old.energy.rows() != d ||
        old.energy.cols() != d || !finite(old.energy)) {
      energy_status = Status::Error(
          StatusCode::kInvalidArgument,
          "CovarianceBounds::set_recovery: old-state energy of blocks [1, " +
              std::to_string(old.old_end) + ") is " + shape(old.energy) + ", expected finite " +
              std::to_string(d) + "x" + std::to_string(d) + " and at most " +
              std::to_string(num_states) + " blocks");
      return k12;
    }
    // K3 (certificate.h): O = [1, old_end), T = {0} ∪ [old_end, n).
    const double a = lambda_max_scaled(padded(old.energy, options_.rounding_margin), W);
    const double b = (1 + num_states - old.old_end) *
                     lambda_max_scaled(weighted_residual(residual, old.old_end, num_states, W), W);
    return std::min(k12, kappa_squared_split(a, b));
  };
  const Status s = set_recovery_with(sigma_rr, spectral, num_states, kappa_squared);
  return s.ok() ? energy_status : s;
}

Eigen::MatrixXd CovarianceBounds::weighted_residual(const Eigen::Ref<const Eigen::MatrixXd>& R,
                                                    int first, int last,
                                                    const Eigen::MatrixXd& W) const {
  return weighted_block_gram(R, first, last, W, [&](int j) -> const Eigen::MatrixXd& {
    return entries_[static_cast<size_t>(j)].bound;
  });
}

Status CovarianceBounds::set_recovery_with(
    const Eigen::MatrixXd& sigma_rr, double residual_frobenius, int num_states,
    const std::function<double(const Eigen::MatrixXd&)>& kappa_squared) {
  if (sigma_rr.rows() != block_dim_ || sigma_rr.cols() != block_dim_ || !finite(sigma_rr) ||
      !(residual_frobenius >= 0.0) || !std::isfinite(residual_frobenius)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::set_recovery: Σ_rr " + shape(sigma_rr) +
                             " must be finite and of block size, residual " +
                             std::to_string(residual_frobenius) + " finite and >= 0");
  }
  if (options_.certify_truncation && num_bounds_ != num_states - 1) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::set_recovery: the filter has " +
                             std::to_string(num_states - 1) + " delayed states but " +
                             std::to_string(num_bounds_) +
                             " have bounds; the certificate needs every state (insert on every "
                             "augmentation)");
  }
  apply_pending_growth();
  sigma_rr_hat_ = symmetric(sigma_rr);
  residual_frobenius_ = residual_frobenius;
  ++epoch_;  // bounds stored from now on are tightened within this snapshot
  certificate_lambda_ = lambda_max_sigma_bound();
  certificate_robot_bound_ = robot_bound_;
  if (!options_.certify_truncation) {
    kappa_ = 0.0;
    set_robot_bound(sigma_rr_hat_);
    return Status::Ok();
  }
  kappa_ = residual_frobenius > 0.0 ? std::sqrt(std::max(0.0, kappa_squared(robot_bound_))) : 0.0;
  if (!std::isfinite(kappa_)) kappa_ = std::numeric_limits<double>::max();
  kappa_ = std::max(kappa_, options_.rounding_margin);
  const Eigen::MatrixXd candidate = sigma_rr_hat_ + kappa_ * certificate_robot_bound_;
  if (candidate.trace() < robot_bound_.trace()) set_robot_bound(candidate);
  return Status::Ok();
}

Status CovarianceBounds::refresh_exact(const ExactMarginals& exact, int num_states) {
  if (exact.block_dim() != block_dim_ || exact.num_blocks() != num_states ||
      num_bounds_ != num_states - 1) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::refresh_exact: marginals of " +
                             std::to_string(exact.num_blocks()) + " blocks of size " +
                             std::to_string(exact.block_dim()) + " for a filter of " +
                             std::to_string(num_states) + " blocks of size " +
                             std::to_string(block_dim_) + " with " + std::to_string(num_bounds_) +
                             " bounds");
  }
  set_robot_bound(padded(exact.marginal(0), options_.rounding_margin));
  for (int j = 1; j < num_states; ++j) reset_to_exact(j, exact.marginal(j));
  pending_growth_ = 0.0;  // every bound is of the current Λ now
  return Status::Ok();
}

Status CovarianceBounds::refresh_exact(const Eigen::Ref<const Eigen::MatrixXd>& marginals,
                                       int num_states, const BoundsSnapshot* since) {
  const int d = block_dim_;
  const auto blocks = static_cast<int>(marginals.rows() / d);
  bool ok = marginals.cols() == d && marginals.rows() % d == 0 && blocks >= 1 &&
            blocks <= num_states && marginals.allFinite();
  for (int j = 1; ok && j < blocks; ++j) ok = contains(j);
  if (!ok) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::refresh_exact: earlier marginals of shape " +
                             shape(marginals) + " (finite, a multiple of " + std::to_string(d) +
                             " rows by " + std::to_string(d) + ", every state with a bound) " +
                             "for a filter of " + std::to_string(num_states) + " blocks");
  }
  if (since == nullptr) {
    for (int j = 1; j < blocks; ++j) reset_to_exact(j, marginals.middleRows(j * d, d));
    return Status::Ok();
  }
  // The rounding of the predictions after that Λ, less what the next set_recovery applies.
  const double grow = std::exp(std::max(0.0, growth_total_ - pending_growth_ - since->growth));
  for (int j = 1; j < blocks; ++j) {
    const Eigen::MatrixXd marginal = grow * marginals.middleRows(j * d, d);
    // A link since the snapshot tightened j: both bound Σ_jj now; the smaller trace stays.
    const Entry& e = entries_[static_cast<size_t>(j)];
    if (e.stored_epoch > since->epoch &&
        e.bound.trace() <= padded(marginal, options_.rounding_margin).trace()) {
      continue;
    }
    reset_to_exact(j, marginal);
  }
  return Status::Ok();
}

void CovarianceBounds::reset_to_exact(int state, const Eigen::MatrixXd& exact_marginal) {
  Entry& e = entries_[static_cast<size_t>(state)];
  lambda_sum_ -= e.lambda_max;
  e.bound = padded(exact_marginal, options_.rounding_margin);
  e.lambda_max = std::max(0.0, lambda_max_symmetric(e.bound));
  lambda_sum_ += e.lambda_max;
  e.snapshot_bound.resize(0, 0);
  e.snapshot_lambda_max = 0.0;
  e.snapshot_epoch = -1;
}

Status CovarianceBounds::propose(int state, const Eigen::MatrixXd& sigma_ir,
                                 LinkProposal* proposal) const {
  if (!contains(state)) {
    return Status::Error(StatusCode::kUnknownState,
                         "CovarianceBounds::propose: state " + std::to_string(state) +
                             " has no bound (never inserted)");
  }
  if (sigma_ir.rows() != block_dim_ || sigma_ir.cols() != block_dim_ || !finite(sigma_ir)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::propose: Σ_ir must be finite " +
                             std::to_string(block_dim_) + "x" + std::to_string(block_dim_) +
                             ", got " + shape(sigma_ir));
  }
  const Entry& e = entries_[static_cast<size_t>(state)];
  // A bound tightened by a link of this snapshot is not a bound of the snapshot's Σ_ii.
  const bool tightened_now = e.snapshot_epoch == epoch_;
  const Eigen::MatrixXd& snapshot_bound = tightened_now ? e.snapshot_bound : e.bound;
  const int d = block_dim_;
  proposal->state = state;
  proposal->kappa = kappa_;
  proposal->joint.resize(2 * d, 2 * d);
  proposal->joint.topLeftCorner(d, d) = sigma_rr_hat_ + (2.0 * kappa_) * certificate_robot_bound_;
  proposal->joint.bottomLeftCorner(d, d) = sigma_ir;
  proposal->joint.topRightCorner(d, d) = sigma_ir.transpose();
  proposal->joint.bottomRightCorner(d, d) = (1.0 + kappa_) * snapshot_bound;
  return Status::Ok();
}

Status CovarianceBounds::offset_covariance_2d(int state, const Eigen::Matrix2d& sigma_ir_top_left,
                                              Eigen::Matrix2d* covariance) const {
  if (!contains(state) || block_dim_ < 2) {
    return Status::Error(StatusCode::kUnknownState,
                         "CovarianceBounds::offset_covariance_2d: state " +
                             std::to_string(state) + " has no bound (never inserted)");
  }
  const Entry& e = entries_[static_cast<size_t>(state)];
  const bool tightened_now = e.snapshot_epoch == epoch_;  // as in propose()
  const Eigen::MatrixXd& snapshot_bound = tightened_now ? e.snapshot_bound : e.bound;
  const Eigen::Matrix2d rr = sigma_rr_hat_.topLeftCorner<2, 2>() +
                             (2.0 * kappa_) * certificate_robot_bound_.topLeftCorner<2, 2>();
  const Eigen::Matrix2d ii = (1.0 + kappa_) * snapshot_bound.topLeftCorner<2, 2>();
  const Eigen::Matrix2d& ir = sigma_ir_top_left;
  *covariance = rr + ii - ir - ir.transpose();
  return Status::Ok();
}

Status CovarianceBounds::update_robot(const Eigen::MatrixXd& H, const Eigen::MatrixXd& R) {
  if (H.cols() != block_dim_ || R.rows() != H.rows() || R.cols() != H.rows()) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::update_robot: H must be m x " +
                             std::to_string(block_dim_) + " and R m x m");
  }
  Eigen::MatrixXd posterior;
  if (!joseph(robot_bound_, H, R, &posterior)) {
    return Status::Error(StatusCode::kNotPositiveDefinite,
                         "CovarianceBounds::update_robot: innovation covariance not SPD");
  }
  // A Kalman update only shrinks the bound (B+ <= B), so a cached λmax(B) stays a valid upper
  // bound of λmax(B+) for L and ε (bounds.h C1); without one, λmax(B+) is computed when L is
  // next read (robot_lambda_max).
  robot_bound_ = symmetric(posterior);
  return Status::Ok();
}

bool CovarianceBounds::joseph(const Eigen::MatrixXd& joint, const Eigen::MatrixXd& H,
                              const Eigen::MatrixXd& R, Eigen::MatrixXd* posterior) {
  if (!finite(joint)) return false;
  const Eigen::MatrixXd PHt = joint * H.transpose();
  const Eigen::MatrixXd S = symmetric(H * PHt + R);
  Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::MatrixXd K = llt.solve(PHt.transpose()).transpose();  // P Hᵀ S⁻¹
  const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(joint.rows(), joint.cols()) - K * H;
  *posterior = IKH * joint * IKH.transpose() + K * R * K.transpose();
  return finite(*posterior);
}

Status CovarianceBounds::update(const LinkProposal& proposal, const Eigen::MatrixXd& H_r,
                                const Eigen::MatrixXd& H_i, const Eigen::MatrixXd& R) {
  const int d = block_dim_;
  const Eigen::Index m = R.rows();
  if (!contains(proposal.state) || proposal.joint.rows() != 2 * d ||
      proposal.joint.cols() != 2 * d) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::update: proposal for state " +
                             std::to_string(proposal.state) + " is not a valid propose() result");
  }
  if (R.cols() != m || H_r.rows() != m || H_i.rows() != m || H_r.cols() != d ||
      H_i.cols() != d || !finite(H_r) || !finite(H_i) || !finite(R)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "CovarianceBounds::update: H_r " + shape(H_r) + ", H_i " + shape(H_i) +
                             ", R " + shape(R) + " must be finite, m x " + std::to_string(d) +
                             " and m x m");
  }
  Eigen::MatrixXd H(m, 2 * d);
  H << H_r, H_i;
  Eigen::MatrixXd best_ii, best_rr, posterior;
  auto consider = [&](const Eigen::MatrixXd& joint) {
    if (!joseph(joint, H, R, &posterior)) return;
    const Eigen::MatrixXd ii = symmetric(posterior.bottomRightCorner(d, d));
    const Eigen::MatrixXd rr = symmetric(posterior.topLeftCorner(d, d));
    if (best_ii.size() == 0 || ii.trace() < best_ii.trace()) best_ii = ii;
    if (best_rr.size() == 0 || rr.trace() < best_rr.trace()) best_rr = rr;
  };
  consider(proposal.joint);
  if (options_.certify_truncation) {
    // Correlation-free candidates (covariance intersection, see the file comment).
    const Eigen::MatrixXd& b_ii = entries_[static_cast<size_t>(proposal.state)].bound;
    Eigen::MatrixXd joint = Eigen::MatrixXd::Zero(2 * d, 2 * d);
    for (double omega : {0.2, 0.35, 0.5, 0.65, 0.8}) {
      joint.topLeftCorner(d, d) = robot_bound_ / omega;
      joint.bottomRightCorner(d, d) = b_ii / (1.0 - omega);
      consider(joint);
    }
  }
  if (best_ii.size() == 0) {
    return Status::Error(StatusCode::kNotPositiveDefinite,
                         "CovarianceBounds::update: innovation covariance of the link to state " +
                             std::to_string(proposal.state) +
                             " is not positive definite (proposal joint not PSD: stale recovery?)"
                             "; bound left unchanged");
  }
  if (options_.certify_truncation) {
    // The update's own rounding, like the exact refresh's: a posterior along a strongly
    // measured direction keeps a margin of only about κ·(posterior / prior) over the filter's
    // marginal, which the Joseph form's rounding can exceed (docs/consistency.md "Rounding
    // margin after an update").
    best_ii = padded(best_ii, options_.rounding_margin);
    best_rr = padded(best_rr, options_.rounding_margin);
  }
  store(proposal.state, best_ii);
  if (options_.certify_truncation && best_rr.trace() < robot_bound_.trace()) {
    set_robot_bound(best_rr);
  }
  return Status::Ok();
}

bool CovarianceBounds::contains(int state) const {
  return state >= 0 && static_cast<size_t>(state) < entries_.size() &&
         entries_[static_cast<size_t>(state)].present;
}

const Eigen::MatrixXd& CovarianceBounds::bound(int state) const {
  if (!contains(state)) {
    throw std::out_of_range("CovarianceBounds::bound: state " + std::to_string(state) +
                            " has no bound");
  }
  return entries_[static_cast<size_t>(state)].bound;
}

}  // namespace nav::core
