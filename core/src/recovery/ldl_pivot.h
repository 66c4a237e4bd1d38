#pragma once
// A new diagonal block of Λ set in a simplicial LDLᵀ factor in place, when no later row depends
// on that block. Internal to nav_core (kept_equal_factor.cpp).
//
// With Λ = L D Lᵀ and the rows [f, f + d) of a block b, the factor's columns before f do not
// depend on Λ_bb, and the pivot block holds its Schur complement: L_bb D_b L_bbᵀ =
// Λ_bb − Σ_{j<f} L_bj D_j L_bjᵀ. If every row after the block has a zero numerator in the
// block's columns (stored as L_ib = 0), those entries stay zero whatever the pivot is. So a new
// Λ_bb changes only L_bb and D_b: a dense d x d factorisation of that Schur complement, with
// the older columns' sum read from the rows of b (one look at the end of each column, whose
// rows CHOLMOD keeps sorted), instead of deleting and re-adding the block's rows, whose row
// additions are sparse triangular solves over its whole reach (Davis & Hager, SIMAX 26(3),
// 2005). The sum is the one a row addition forms; the old pivot block plus the change of Λ_bb
// is not used, since a short prediction's information in the old block would cancel in it.

#include <Eigen/Core>

#include "ldl_solve.h"

namespace nav::core::detail {

/// Makes the pivot block of rows [first, first + diagonal.rows()) of `L` (value array `value`,
/// L.value writable) that of a Λ whose diagonal block there is `diagonal`, the rest of Λ as the
/// factor holds it. Returns false and leaves the factor as it was when a stored value below the
/// block in its columns is not zero, an entry of the block's lower triangle is not stored, or a
/// new pivot is not positive (the caller then deletes and re-adds the block's rows).
bool set_pivot_block(const SimplicialLdl& L, double* value, int first,
                     const Eigen::MatrixXd& diagonal);

/// Dense LDLᵀ without pivoting (the factor's order is fixed) of the lower triangle of `a`:
/// `unit` unit lower triangular, `pivot` the diagonal of D. False when a pivot is not positive.
bool dense_ldl(const Eigen::MatrixXd& a, Eigen::MatrixXd* unit, Eigen::VectorXd* pivot);

}  // namespace nav::core::detail
