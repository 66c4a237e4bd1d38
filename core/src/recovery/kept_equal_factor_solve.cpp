// Solves with the kept factor: Λ⁻¹ of any right-hand sides, and the robot's covariance column
// with or without a step of the mean (recovery/kept_equal_factor.h), on the row-major kernels
// of ldl_solve.h.
#include <cstddef>

#include "ldl_solve.h"
#include "nav/core/recovery/kept_equal_factor.h"

namespace nav::core {

void KeptEqualFactor::gather_slots(Eigen::Ref<Eigen::MatrixXd> Z, int width) const {
  const int d = factored_.block_dim();
  for (int b = 0; b < factored_.num_blocks(); ++b) {
    for (int i = 0; i < d; ++i) {
      const double* y = rows_.data() + static_cast<std::ptrdiff_t>(slot_row(b, i)) * width;
      for (Eigen::Index c = 0; c < Z.cols(); ++c) Z(Eigen::Index{b} * d + i, c) = y[c];
    }
  }
}

void KeptEqualFactor::scatter_slots(const Eigen::Ref<const Eigen::MatrixXd>& R, double* rows,
                                    int width) const {
  const int d = factored_.block_dim();
  for (int b = 0; b < factored_.num_blocks(); ++b) {
    for (int i = 0; i < d; ++i) {
      double* y = rows + static_cast<std::ptrdiff_t>(slot_row(b, i)) * width;
      for (Eigen::Index c = 0; c < R.cols(); ++c) y[c] = R(Eigen::Index{b} * d + i, c);
    }
  }
}

void KeptEqualFactor::apply(const Eigen::Ref<const Eigen::MatrixXd>& R,
                            Eigen::Ref<Eigen::MatrixXd> Z) const {
  const int width = detail::ldl_width(static_cast<int>(R.cols()));
  const detail::SimplicialLdl L = ldl();
  rows_.assign(static_cast<size_t>(L.n) * static_cast<size_t>(width), 0.0);
  scatter_slots(R, rows_.data(), width);
  detail::ldl_forward_diagonal(L, rows_.data(), width, static_cast<int>(R.cols()));
  last_solve_supernodes_ =
      detail::ldl_backward_blocks(L, factored_.block_dim(), rows_.data(), width);
  gather_slots(Z, width);
}

void KeptEqualFactor::solve_robot_columns(Eigen::Ref<Eigen::MatrixXd> Z) const {
  const int width = detail::ldl_width(factored_.block_dim());
  rows_.assign(static_cast<size_t>(ldl().n) * static_cast<size_t>(width), 0.0);
  robot_columns_backward(width, 0);
  gather_slots(Z, width);
}

void KeptEqualFactor::solve_with_robot_columns(const Eigen::Ref<const Eigen::VectorXd>& r,
                                               Eigen::Ref<Eigen::MatrixXd> Z) const {
  const int d = factored_.block_dim();
  const detail::SimplicialLdl L = ldl();
  // The forward pass of r alone, on a compact vector (its scattered updates then stay in cache).
  forward_.assign(static_cast<size_t>(L.n), 0.0);
  scatter_slots(r, forward_.data(), 1);
  detail::ldl_forward_diagonal(L, forward_.data(), 1, 1);
  const int width = detail::ldl_width(1 + d);
  rows_.assign(static_cast<size_t>(L.n) * static_cast<size_t>(width), 0.0);
  for (int j = 0; j < L.n; ++j)
    rows_[static_cast<size_t>(j) * width] = forward_[static_cast<size_t>(j)];
  robot_columns_backward(width, 1);
  gather_slots(Z, width);
}

void KeptEqualFactor::robot_columns_backward(int width, int offset) const {
  const int d = factored_.block_dim();
  const int first = slot_row(0, 0);
  const detail::SimplicialLdl L = ldl();
  // The robot's diagonal block of L D Lᵀ: unit lower L_rr and D_r (each column of a simplicial
  // LDLᵀ factor starts with its D entry; the robot's columns have no rows below its block).
  Eigen::MatrixXd unit_lower = Eigen::MatrixXd::Identity(d, d);
  Eigen::VectorXd pivots(d);
  for (int j = 0; j < d; ++j) {
    const int start = L.p[first + j];
    pivots[j] = L.value[start];
    for (int k = start + 1; k < start + L.nz[first + j]; ++k) {
      unit_lower(L.row[k] - first, j) = L.value[k];
    }
  }
  // Forward and diagonal passes of E_r: D_r⁻¹ L_rr⁻¹ in the robot's rows, zero above them.
  const Eigen::MatrixXd inverse =
      pivots.cwiseInverse().asDiagonal() *
      unit_lower.triangularView<Eigen::UnitLower>().solve(Eigen::MatrixXd::Identity(d, d));
  for (int i = 0; i < d; ++i) {
    double* y = rows_.data() + static_cast<std::ptrdiff_t>(first + i) * width + offset;
    for (int c = 0; c < d; ++c) y[c] = inverse(i, c);
  }
  // Lᵀ X = ·, one pass over the factor
  last_solve_supernodes_ = detail::ldl_backward_blocks(L, d, rows_.data(), width);
}

}  // namespace nav::core
