#pragma once
// Factor preconditioner for the state recovery (state_recovery.h): a sparse Cholesky factor of
// Λ taken at a refresh, reused as the PCG preconditioner for the following steps.
//
// Between two refreshes the filter's Λ differs from the factored Λ₀ (n₀ = its dimension, k =
// n₀/d): block 0 (the robot) is a new state after every prediction, the robot of the refresh
// became the delayed state appended first (block k), later states follow, and camera links add
// rank-5 terms. The preconditioner maps Λ₀'s robot block onto block k (a symmetric
// permutation P) and treats T = {0} ∪ {blocks after k} (the robot and the newer states) as one
// dense block:
//     M = blkdiag(P Λ₀ Pᵀ, Λ_TT)     (before any prediction since the refresh: M = Λ₀ = Λ)
// Λ_TT (the robot, the new states, their chain and links among them; (1 + new states)·d
// square) is factored by LLT every step. M is SPD, so PCG (pcg.h) stays exact in exact
// arithmetic whatever the mapping; Λ − M is the prediction and link information added since
// the refresh plus the coupling between T and the rest, of low rank, so PCG needs few
// iterations per step (measured: docs/consistency.md). Where the filter marginalises the robot
// between refreshes (predictions without a kept state), block k is the robot of a later time
// than Λ₀'s block 0: M is then an approximation of Λ, still SPD.
//
// Refresh: CHOLMOD supernodal Cholesky (block AMD ordering) plus the selected inversion of
// ExactMarginals, so that every refresh also yields the exact marginals Σ_ii of that Λ (the
// exact refresh of the covariance bounds, bounds.h). The pattern grows by a state per image,
// so every refresh analyses the pattern again (AMD on the block graph: a small part of the
// factorisation's cost).
//
// Not thread-safe (the factor's solve workspace): owned by the recovery thread.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/recovery/certificate.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/recovery/pcg.h"
#include "nav/core/status.h"

namespace nav::core {

class FactorPreconditioner final : public Preconditioner {
 public:
  FactorPreconditioner() = default;
  /// A copy carries no factor: it refactors at its first use (a checkpointed or copied filter
  /// continues with an exact refresh).
  FactorPreconditioner(const FactorPreconditioner&) {}
  FactorPreconditioner& operator=(const FactorPreconditioner& other) {
    if (this != &other) reset();
    return *this;
  }
  FactorPreconditioner(FactorPreconditioner&&) noexcept = default;
  FactorPreconditioner& operator=(FactorPreconditioner&&) noexcept = default;

  /// Factors Λ (and runs the selected inversion). kNotPositiveDefinite (the previous factor
  /// dropped) when CHOLMOD finds a non-positive pivot.
  Status refresh(const Eigen::SparseMatrix<double>& lambda, int block_dim);
  /// Takes exact marginals computed elsewhere (lagged_renewal.h) as the factor of their Λ.
  void adopt(std::shared_ptr<const ExactMarginals> marginals);
  /// Re-targets the preconditioner to the current Λ: factors Λ_TT (the robot and the states
  /// appended after block k, when the robot changed since the refresh). kInvalidArgument if there is no factor, the block size
  /// differs or Λ is smaller than the factor; kNotPositiveDefinite if Λ_TT is not SPD.
  Status update_trailing(const InformationMatrix& lambda);
  /// Drops the factor (the next solve must refresh).
  void reset();

  bool has_factor() const { return factor_ != nullptr; }
  /// Dimension of the factored Λ₀.
  Eigen::Index factored_dim() const { return factored_dim_; }
  Eigen::Index dim() const override { return dim_; }
  /// The exact marginals of the last refresh (null without a factor).
  const ExactMarginals* marginals() const { return factor_.get(); }
  /// The certificate's K3 input (certificate.h) for a residual R (n x d, n >= the factored
  /// dimension): R_Oᵀ Σ₀_OO R_O over the rows of blocks O = [1, k), k = the factored blocks
  /// (Λ₀'s robot, block 0, left out), by one forward solve with the factor. old_end = 0
  /// without a factor or when R is shorter than Λ₀.
  OldStateEnergy old_state_energy(const Eigen::Ref<const Eigen::MatrixXd>& R) const;

  void apply(const Eigen::Ref<const Eigen::MatrixXd>& R,
             Eigen::Ref<Eigen::MatrixXd> Z) const override;

 private:
  std::shared_ptr<const ExactMarginals> factor_;
  int block_dim_ = 0;
  Eigen::Index factored_dim_ = 0;
  Eigen::Index dim_ = 0;
  Eigen::LLT<Eigen::MatrixXd> tail_;  // Λ_TT (empty before the first prediction since refresh)
  mutable Eigen::MatrixXd rhs_, y_, tail_rhs_;
};

}  // namespace nav::core
