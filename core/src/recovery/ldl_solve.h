#pragma once
// Triangular solves with a simplicial LDLᵀ factor in CHOLMOD's column storage, on right-hand
// sides stored by rows (row i's `width` values contiguous), so that every entry of L read
// updates all columns at once with vector operations. Internal to nav_core (kept_equal_factor.cpp).
//
// CHOLMOD's simplicial solves (cholmod_solve) take the right-hand sides four columns at a time,
// so a 12-column backward pass reads the whole factor three times; here it is read once. The
// arithmetic is the same column-oriented algorithm (Davis, "Direct Methods for Sparse Linear
// Systems", SIAM 2006, ch. 3): forward by scatter, backward by gather.

namespace nav::core::detail {

/// Column j of the unit lower L holds nz[j] entries from p[j] in `row` / `value`, the first on
/// the diagonal, where it stores D_j (cholmod_factor with is_ll = 0, is_super = 0).
struct SimplicialLdl {
  int n = 0;
  const int* p = nullptr;
  const int* nz = nullptr;
  const int* row = nullptr;
  const double* value = nullptr;
};

/// The row width the solves below accept for `columns` right-hand sides: 1, or a multiple of 4
/// (the added columns are zero and stay zero).
int ldl_width(int columns);

/// Y ← D⁻¹ L⁻¹ Y in place in the first `columns` columns (rounded up to a multiple of 4 when
/// width > 1; the others are left as they are), Y of L.n rows of `width` (ldl_width) doubles.
/// With width 1 a column of L is skipped when its entry of Y is zero as it is reached: a sparse
/// Y reads only its reach, the union of its nonzeros' paths up the elimination tree (Gilbert and
/// Peierls; Davis 2006, sec. 3.2).
void ldl_forward_diagonal(const SimplicialLdl& L, double* Y, int width, int columns);

/// Y ← L⁻ᵀ Y in place (the backward pass), Y as above.
void ldl_backward(const SimplicialLdl& L, double* Y, int width);

/// ldl_backward for a factor of d x d blocks (d <= 12, L.n a multiple of d): a block whose
/// columns share their rows below it (a supernode, what the factor of a block matrix holds
/// unless a modification gave one column a pattern of its own) is solved as one: each row
/// below it is gathered once per 3 of its columns instead of once per column (the supernodal
/// solve of Ng and Peyton, SIAM J. Sci. Comput. 14(5), 1993, on the blocks the simplicial
/// factor keeps: its row modifications need the simplicial form). Returns the
/// number of blocks so solved; the others (and any d that does not apply) column by column.
int ldl_backward_blocks(const SimplicialLdl& L, int block_dim, double* Y, int width);

}  // namespace nav::core::detail
