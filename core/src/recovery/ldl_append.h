#pragma once
// A block of rows appended to a simplicial LDLᵀ factor as one block, when nothing after the
// block depends on it. Internal to nav_core (kept_equal_factor.cpp).
//
// Appending a block b whose couplings all lie in earlier rows leaves every earlier column's
// own values unchanged and adds b's rows to them: with A_b the block's column of Λ above its
// diagonal, L_{<b} Y = A_b (a sparse forward solve over the reach of A_b's rows in the
// elimination tree), L_bj = Y_jᵀ / D_j, and the pivot block is the Schur complement
// L_bb D_b L_bbᵀ = Λ_bb − Σ_j Y_j Y_jᵀ / D_j (Davis & Hager, SIMAX 26(3), 2005, the row
// addition). CHOLMOD's cholmod_rowadd forms the same rows one at a time, walking the reach and
// shifting every column once per row; here the reach is walked once for all d rows, the
// forward solve carries d right-hand sides, and each column is shifted once.

#include <cholmod.h>

#include <Eigen/Core>
#include <vector>

namespace nav::core::detail {

/// One present neighbour of the appended block: its first row in the factor and the coupling
/// Λ_{b,nb} (rows: the appended block, columns: the neighbour), d x d.
struct AppendCoupling {
  int first_row = 0;
  Eigen::MatrixXd block;
};

enum class AppendResult {
  kAppended,       ///< the block's rows and pivot block are in the factor
  kNotApplicable,  ///< the factor is unchanged; the caller adds the rows another way
  kOutOfMemory,    ///< CHOLMOD could not grow a column: the factor is lost (c->status says)
};

/// Appends the block of rows [first, first + diagonal.rows()) of a simplicial LDLᵀ factor `L`
/// (is_ll = 0, is_super = 0, rows of each column sorted) with diagonal block `diagonal` and the
/// couplings `couplings`. Not applicable, the factor untouched, when a neighbour's rows are not
/// all before `first`, a column of the block is not an identity column, a column in the reach
/// already stores a row of the block or a nonzero value in a row after it, or a new pivot is
/// not positive.
AppendResult append_block(cholmod_factor* L, cholmod_common* c, int first,
                          const Eigen::MatrixXd& diagonal,
                          const std::vector<AppendCoupling>& couplings);

}  // namespace nav::core::detail
