#pragma once
// Λμ kept from one step of the state recovery to the next, for the mean's residual
// r₀ = η − Λμ (state_recovery.h "kept_step"). Between two steps the filter changes few block
// rows of Λ (the robot and its neighbours, the appended states, the endpoints of new links:
// kept_equal_factor.h) and few blocks of the warm start μ (the robot's and the appended states':
// state_recovery.h "Warm-start extension"). Row i of Λμ, Σ_j Λ_ij μ_j, changes only if row i
// of Λ changed or μ_j changed for some j with Λ_ij ≠ 0; every other row holds what the previous
// product computed from the same numbers. So instead of a product with all of Λ (it read the
// whole matrix at every image), only those rows are recomputed.
//
// The caller names the changed rows of Λ (or says they are unknown: then the whole product is
// due) and the blocks of μ it moved; a base set by the previous step's product is valid for the
// next step only (`stamp`), so any other solve in between makes it stale.
#include <Eigen/Core>
#include <vector>

#include "nav/core/filter/information_matrix.h"

namespace nav::core {

class MeanProduct {
 public:
  /// Forgets the base (μ replaced, or a solve that does not keep it).
  void invalidate() { valid_ = false; }
  /// μ's block `block` changed since the base was set (kept only while there is a base).
  void moved(int block);
  /// The base: `product` = Λμ of the step stamped `stamp`.
  void set(const Eigen::Ref<const Eigen::VectorXd>& product, long stamp);
  /// `out` = Λμ for the step stamped `stamp` from the base set at stamp − 1: the rows in
  /// `changed_rows` (block rows of Λ that changed; nullptr: unknown), in the moved blocks and
  /// in their neighbours in `lambda` recomputed, the others copied. Returns the block rows
  /// recomputed, or −1 (out untouched) when the base is stale or the changed rows unknown.
  int update(const InformationMatrix& lambda, const std::vector<int>* changed_rows,
             const Eigen::Ref<const Eigen::VectorXd>& mean, long stamp,
             Eigen::Ref<Eigen::VectorXd> out);

 private:
  Eigen::VectorXd base_;
  std::vector<int> moved_;
  std::vector<char> due_;  // block rows to recompute (scratch)
  long stamp_ = 0;
  bool valid_ = false;
};

}  // namespace nav::core
