// Algorithm 1 of Eustice et al. (RSS 2005) with certified inflation (see recovery/bounds.h).
#include "nav/core/recovery/bounds.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
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

}  // namespace

double lambda_max_symmetric(const Eigen::MatrixXd& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(symmetric(m), Eigen::EigenvaluesOnly);
  return solver.eigenvalues().maxCoeff();
}

CovarianceBounds::CovarianceBounds(int block_dim, BoundsOptions options)
    : block_dim_(block_dim), options_(options) {
  if (block_dim < 1) {
    throw std::invalid_argument("CovarianceBounds: block_dim must be >= 1, got " +
                                std::to_string(block_dim));
  }
}

void CovarianceBounds::set_robot_bound(const Eigen::MatrixXd& bound) {
  robot_bound_ = symmetric(bound);
  robot_lambda_max_ = std::max(0.0, lambda_max_symmetric(robot_bound_));
}

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
  certificate_lambda_ = 0.0;
  lambda_sum_ = 0.0;
  set_robot_bound(P0);
  sigma_rr_hat_ = robot_bound_;
  residual_frobenius_ = 0.0;
  epsilon_robot_ = 0.0;
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
  if (keep_current) {
    if (Status s = insert(kept_state); !s.ok()) return s;
  }
  set_robot_bound(F * robot_bound_ * F.transpose() + Q);
  return Status::Ok();
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

double CovarianceBounds::epsilon(double lambda_max_block) const {
  if (!options_.certify_truncation) return 0.0;
  return std::sqrt(std::max(0.0, lambda_max_block) * certificate_lambda_) * residual_frobenius_;
}

Status CovarianceBounds::set_recovery(const Eigen::MatrixXd& sigma_rr, double residual_frobenius,
                                      int num_states) {
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
  sigma_rr_hat_ = symmetric(sigma_rr);
  residual_frobenius_ = residual_frobenius;
  ++epoch_;  // bounds stored from now on are tightened within this snapshot
  certificate_lambda_ = lambda_max_sigma_bound();
  if (!options_.certify_truncation) {
    epsilon_robot_ = 0.0;
    set_robot_bound(sigma_rr_hat_);
    return Status::Ok();
  }
  epsilon_robot_ = epsilon(robot_lambda_max_);
  const Eigen::MatrixXd candidate =
      sigma_rr_hat_ + epsilon_robot_ * Eigen::MatrixXd::Identity(block_dim_, block_dim_);
  if (candidate.trace() < robot_bound_.trace()) set_robot_bound(candidate);
  return Status::Ok();
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
  const double snapshot_lambda = tightened_now ? e.snapshot_lambda_max : e.lambda_max;
  const int d = block_dim_;
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(d, d);
  proposal->state = state;
  proposal->epsilon_robot = epsilon_robot_;
  proposal->epsilon_state = epsilon(snapshot_lambda);
  proposal->joint.resize(2 * d, 2 * d);
  proposal->joint.topLeftCorner(d, d) =
      sigma_rr_hat_ + (proposal->epsilon_robot + proposal->epsilon_state) * I;
  proposal->joint.bottomLeftCorner(d, d) = sigma_ir;
  proposal->joint.topRightCorner(d, d) = sigma_ir.transpose();
  proposal->joint.bottomRightCorner(d, d) = snapshot_bound + proposal->epsilon_state * I;
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
  const double snapshot_lambda = tightened_now ? e.snapshot_lambda_max : e.lambda_max;
  const double epsilon_state = epsilon(snapshot_lambda);
  const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
  const Eigen::Matrix2d rr =
      sigma_rr_hat_.topLeftCorner<2, 2>() + (epsilon_robot_ + epsilon_state) * I;
  const Eigen::Matrix2d ii = snapshot_bound.topLeftCorner<2, 2>() + epsilon_state * I;
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
  // A Kalman update only shrinks the bound (B+ <= B), so the stored λmax(B) stays a valid upper
  // bound of λmax(B+) for L and ε (bounds.h C1): no eigen-solve per measurement. It is
  // recomputed at the next predict_robot / set_recovery.
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
