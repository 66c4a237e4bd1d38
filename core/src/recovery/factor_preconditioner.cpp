// Factor preconditioner: blkdiag(P Λ₀ Pᵀ, Λ_TT) from the refreshed factor of Λ₀ and a dense LLT
// of the robot and the newer states (recovery/factor_preconditioner.h).
#include "nav/core/recovery/factor_preconditioner.h"

#include <string>
#include <vector>

namespace nav::core {

Status FactorPreconditioner::refresh(const Eigen::SparseMatrix<double>& lambda, int block_dim) {
  reset();
  try {
    adopt(std::make_shared<const ExactMarginals>(ExactMarginals::compute(lambda, block_dim)));
  } catch (const std::exception& e) {
    reset();
    return Status::Error(StatusCode::kNotPositiveDefinite,
                         std::string("FactorPreconditioner::refresh: ") + e.what());
  }
  return Status::Ok();
}

void FactorPreconditioner::adopt(std::shared_ptr<const ExactMarginals> marginals) {
  reset();
  if (marginals == nullptr) return;
  block_dim_ = marginals->block_dim();
  factored_dim_ = Eigen::Index{marginals->num_blocks()} * block_dim_;
  dim_ = factored_dim_;
  factor_ = std::move(marginals);
}

void FactorPreconditioner::reset() {
  factor_.reset();
  block_dim_ = 0;
  factored_dim_ = 0;
  dim_ = 0;
}

Status FactorPreconditioner::update_trailing(const InformationMatrix& lambda) {
  if (!has_factor() || lambda.block_dim() != block_dim_ || lambda.dim() < factored_dim_) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "FactorPreconditioner::update_trailing: factor of dimension " +
                             std::to_string(factored_dim_) + " (block " +
                             std::to_string(block_dim_) + ") cannot precondition Λ of " +
                             std::to_string(lambda.dim()) + " (block " +
                             std::to_string(lambda.block_dim()) + ")");
  }
  dim_ = lambda.dim();
  if (dim_ == factored_dim_) return Status::Ok();  // M = Λ₀ (no prediction since the refresh)
  const int d = block_dim_;
  const int k = static_cast<int>(factored_dim_ / d);
  std::vector<int> tail{0};
  for (int b = k + 1; b < lambda.num_blocks(); ++b) tail.push_back(b);
  const auto t = static_cast<Eigen::Index>(tail.size());
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(t * d, t * d);
  for (Eigen::Index a = 0; a < t; ++a) {
    for (Eigen::Index b = 0; b < t; ++b) {
      const int i = tail[static_cast<size_t>(a)], j = tail[static_cast<size_t>(b)];
      const InformationMatrix::Block* block =
          i == j ? &lambda.diagonal_block(i) : lambda.find_block(i, j);
      if (block != nullptr) dense.block(a * d, b * d, d, d) = *block;
    }
  }
  tail_.compute(dense);
  if (tail_.info() != Eigen::Success) {
    return Status::Error(StatusCode::kNotPositiveDefinite,
                         "FactorPreconditioner::update_trailing: Λ over the robot and the " +
                             std::to_string(t - 1) + " states after block " + std::to_string(k) +
                             " is not positive definite");
  }
  return Status::Ok();
}

void FactorPreconditioner::apply(const Eigen::Ref<const Eigen::MatrixXd>& R,
                                 Eigen::Ref<Eigen::MatrixXd> Z) const {
  const Eigen::Index d = block_dim_, n0 = factored_dim_, m = R.cols();
  if (dim_ == n0) {
    factor_->solve(R, Z);
    return;
  }
  // P Λ₀ Pᵀ: Λ₀'s block 0 is block k = n₀/d now (rows n₀ .. n₀ + d).
  rhs_.resize(n0, m);
  rhs_.topRows(d) = R.middleRows(n0, d);
  rhs_.bottomRows(n0 - d) = R.middleRows(d, n0 - d);
  y_.resize(n0, m);
  factor_->solve(rhs_, y_);
  Z.middleRows(n0, d) = y_.topRows(d);
  Z.middleRows(d, n0 - d) = y_.bottomRows(n0 - d);
  // T: block 0 and the rows after block k, dense LLT.
  const Eigen::Index after = dim_ - n0 - d;
  tail_rhs_.resize(d + after, m);
  tail_rhs_.topRows(d) = R.topRows(d);
  tail_rhs_.bottomRows(after) = R.bottomRows(after);
  tail_.solveInPlace(tail_rhs_);
  Z.topRows(d) = tail_rhs_.topRows(d);
  Z.bottomRows(after) = tail_rhs_.bottomRows(after);
}

OldStateEnergy FactorPreconditioner::old_state_energy(
    const Eigen::Ref<const Eigen::MatrixXd>& R) const {
  OldStateEnergy out;
  const Eigen::Index n0 = factored_dim_, d = block_dim_;
  if (!factor_ || R.rows() < n0 || n0 <= d) return out;
  rhs_ = R.topRows(n0);
  rhs_.topRows(d).setZero();  // Λ₀'s robot is not a state of the current Λ
  out.energy = factor_->quadratic_form(rhs_);
  out.old_end = static_cast<int>(n0 / d);
  return out;
}

}  // namespace nav::core
