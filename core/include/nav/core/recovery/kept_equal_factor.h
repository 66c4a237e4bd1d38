#pragma once
// A sparse LDLᵀ factor of the filter's Λ kept equal to Λ from one recovery step to the next by
// modifying it instead of refactoring: the factor preconditioner's kept-equal mode
// (factor_preconditioner.h). With M = Λ one step of iterative refinement (pcg.h
// solve_refinement) is the direct solve.
//
// Method: Davis & Hager, "Modifying a sparse Cholesky factorization" (SIMAX 20(3), 1999) and
// "Row modifications of a sparse Cholesky factorization" (SIMAX 26(3), 2005), as CHOLMOD's
// Modify module implements them on a simplicial LDLᵀ factor (cholmod_updown, cholmod_rowadd,
// cholmod_rowdel). The factor lives in "slot" space: the delayed states present at the last
// refactorisation in AMD order of the block graph, then `spare_blocks` reserved slots whose
// rows are the identity until a state appended later takes them (chronologically, so a new
// state's rows enter at the end and cause no fill above them), then the robot (block 0) last.
// With `recent_blocks` > 0 the order is constrained AMD (CAMD) with the newest `recent_blocks`
// states after all older ones, as iSAM2's incremental ordering puts the most recent variables
// last (Kaess et al., "iSAM2: Incremental smoothing and mapping using the Bayes tree", IJRR
// 31(2), 2012): the next images' links mostly reach those states, so their row additions and
// rank updates run along short paths near the end of the elimination tree instead of through
// it (docs/performance.md "The newest states ordered last").
//
// What changes between two steps of the delayed-state filter (filter/esdf.h), and how each
// change reaches the factor in update():
//   * the robot (block 0) and its neighbours in the previously factored Λ: prediction
//     marginalises the robot (a Schur complement on its neighbours, not a PSD increment) and a
//     kept robot becomes an appended block. Their rows are deleted and re-added whole, except
//     the robot's one neighbour when only its diagonal block changed: with the robot deleted no
//     later row depends on it, so the change reaches only its pivot block, refactored in place
//     (ldl_pivot.h) instead of row additions over its whole reach;
//   * appended blocks: added into the next reserved slots, all rows of a block at once when
//     its couplings lie before it (ldl_append.h: one walk of the reach, one forward solve with
//     the block's columns, one shift of each column), else row by row (cholmod_rowadd);
//   * any other block whose diagonal block changed (the older endpoint of a camera link): the
//     increment ΔΛ over those blocks, PSD under the ESDF's fixed linearisation (a sum of link
//     terms Hᵀ R⁻¹ H), is split per connected group by an eigendecomposition into
//     ΔΛ = C₊C₊ᵀ − C₋C₋ᵀ and applied by a rank update (and a downdate, empty under the premise).
// A change that breaks the premise without touching a diagonal block (a relabelling of states
// that are not the robot's neighbours) is not seen: the factor then differs from Λ, PCG with it
// is still exact in exact arithmetic (M stays SPD), and the recovery's residual test triggers a
// refresh. The certified bounds never depend on the factor being equal to Λ (bounds.h).
//
// Costs per step (docs/performance.md "A factor kept equal to Λ"): row modifications of the
// robot, its neighbours and the appended states, a rank update of about 5 per link, one
// simplicial solve; the O(map) part is the scan of the diagonal blocks.
//
// Not thread-safe (CHOLMOD's workspace): owned by the recovery thread.

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <vector>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/recovery/pcg.h"
#include "nav/core/status.h"

namespace nav::core {
namespace detail {
struct SimplicialLdl;
}  // namespace detail

/// What the last update() did, all zero after factor() or reset() (diagnostics and tests).
struct KeptFactorUpdate {
  int rows_replaced = 0;    ///< blocks deleted and re-added (the robot and its neighbours)
  int pivots_modified = 0;  ///< the robot's neighbour, its change applied to its pivot block
  int rows_added = 0;      ///< appended blocks row-added into reserved slots
  int blocks_appended = 0;  ///< blocks added as one block of rows (src/recovery/ldl_append.h)
  int blocks_updated = 0;  ///< other blocks whose increment was applied by a rank update
  int update_rank = 0;     ///< columns of C₊ (rank update)
  int downdate_rank = 0;   ///< columns of C₋ (downdate; 0 under the PSD premise)
};

class KeptEqualFactor final : public Preconditioner {
 public:
  KeptEqualFactor();
  ~KeptEqualFactor() override;
  /// A copy (or a move) carries no factor: it refactors at its first use, as a checkpointed or
  /// copied recovery does (factor_preconditioner.h).
  KeptEqualFactor(const KeptEqualFactor&);
  KeptEqualFactor& operator=(const KeptEqualFactor& other);

  /// Factors Λ afresh (block 0 the robot, blocks 1.. the delayed states in time order) with
  /// room for `spare_blocks` (>= 0) appended states, the newest `recent_blocks` (>= 0) ordered
  /// last (file comment). kNotPositiveDefinite (no factor kept) when CHOLMOD meets a
  /// non-positive pivot, kInvalidArgument for an empty Λ or a negative count.
  Status factor(const InformationMatrix& lambda, int spare_blocks, int recent_blocks = 0);
  /// Modifies the factor to equal `lambda`: the same filter's Λ some steps later, its blocks
  /// 1 .. factored_blocks()-1 the same states, the blocks after them appended since (file
  /// comment). kOutOfRange when more blocks were appended than reserved slots remain and
  /// kInvalidArgument for another block size or fewer blocks (the factor is kept: refactor);
  /// kNotPositiveDefinite when CHOLMOD fails (the factor is dropped).
  Status update(const InformationMatrix& lambda);
  /// Drops the factor.
  void reset();

  bool has_factor() const;
  /// Blocks of the Λ the factor equals now.
  int factored_blocks() const { return factored_.num_blocks(); }
  /// Reserved slots not taken yet.
  int spare_blocks() const;
  /// The slot (block position in the factor) of `block`, 0 <= block < factored_blocks().
  int slot(int block) const { return slot_[static_cast<size_t>(block)]; }
  const KeptFactorUpdate& last_update() const { return last_update_; }
  /// The blocks whose rows of Λ the last update() found changed (the robot and its neighbours,
  /// the appended states, the blocks of a rank update); nullptr after factor(), reset() or a
  /// failed update (unknown). Under the premise of the file comment.
  const std::vector<int>* rows_changed_by_last_update() const {
    return changed_rows_ ? &*changed_rows_ : nullptr;
  }
  /// Blocks the last solve's backward pass took as supernodes (ldl_solve.h), for the tests.
  int last_solve_supernodes() const { return last_solve_supernodes_; }
  /// Nonzeros of L (fill), for the benchmarks.
  double factor_nnz() const;

  Eigen::Index dim() const override { return factored_.dim(); }
  /// Z = Λ⁻¹ R with the factor (R and Z of dim() rows).
  void apply(const Eigen::Ref<const Eigen::MatrixXd>& R,
             Eigen::Ref<Eigen::MatrixXd> Z) const override;
  /// Z = Λ⁻¹ E_r, the robot's covariance column (dim() x block_dim). The robot holds the last
  /// slot, so L⁻¹ E_r is zero above its rows: the forward pass is a dense block_dim² solve and
  /// only the backward pass reads the whole factor (half of apply(E_r)'s work).
  void solve_robot_columns(Eigen::Ref<Eigen::MatrixXd> Z) const;
  /// Z = [Λ⁻¹ r | Λ⁻¹ E_r] (dim() x (1 + block_dim)): a refinement step of the mean and the
  /// robot's column together, with one forward pass (of r alone) and one backward pass over the
  /// factor for all 1 + block_dim columns.
  void solve_with_robot_columns(const Eigen::Ref<const Eigen::VectorXd>& r,
                                Eigen::Ref<Eigen::MatrixXd> Z) const;

 private:
  struct Cholmod;
  int slot_row(int block, int i) const;
  void delete_block(int block);
  void add_block(const InformationMatrix& lambda, int block);
  bool rank_update(const InformationMatrix& lambda, const std::vector<int>& changed);
  /// Sets `block`'s new diagonal block in its pivot block in place (ldl_pivot.h) if nothing
  /// else of its row changed; false (factor untouched) otherwise.
  bool modify_pivot(const InformationMatrix& lambda, int block);
  void copy_rows(const InformationMatrix& lambda, const std::vector<int>& rows);
  /// The factor's arrays for the row-major solves (ldl_solve.h).
  detail::SimplicialLdl ldl() const;
  /// The robot's columns D_r⁻¹ L_rr⁻¹ into rows_ at column `offset`, then the backward pass.
  void robot_columns_backward(int width, int offset) const;
  /// R (block space) into `rows` (slot space, `width` doubles per row; the others untouched).
  void scatter_slots(const Eigen::Ref<const Eigen::MatrixXd>& R, double* rows, int width) const;
  /// Z (block space) from rows_ (slot space, `width` doubles per row).
  void gather_slots(Eigen::Ref<Eigen::MatrixXd> Z, int width) const;

  std::unique_ptr<Cholmod> factor_;
  InformationMatrix factored_{1};  // Λ as the factor holds it
  std::vector<int> slot_;          // slot_[block]: the block's slot in the factor
  std::vector<char> present_;      // present_[block]: its rows are in the factor now
  int next_slot_ = 0, robot_slot_ = 0;
  KeptFactorUpdate last_update_;
  mutable std::vector<double> rows_;     // right-hand sides by rows, in slot space
  mutable std::vector<double> forward_;  // one right-hand side, in slot space
  mutable int last_solve_supernodes_ = 0;
  std::optional<std::vector<int>> changed_rows_;  // rows_changed_by_last_update()
};

}  // namespace nav::core
