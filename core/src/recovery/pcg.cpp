// Multi-RHS preconditioned CG and its block-Jacobi preconditioner (see recovery/pcg.h).
#include "nav/core/recovery/pcg.h"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <string>

namespace nav::core {
namespace {

/// Makes `m` at least rows x cols (capacity grows by 1.5x so a growing filter reallocates
/// O(log n) times) and returns its top-left rows x cols block.
Eigen::Block<Eigen::MatrixXd> scratch(Eigen::MatrixXd& m, Eigen::Index rows, Eigen::Index cols) {
  if (m.rows() < rows || m.cols() < cols) {
    const Eigen::Index new_rows = std::max(rows, m.rows() + m.rows() / 2);
    m.resize(new_rows, std::max(cols, m.cols()));
  }
  return m.topLeftCorner(rows, cols);
}

double relative(double residual, double rhs) { return rhs > 0.0 ? residual / rhs : residual; }

Status check_sizes(const char* where, const SpdOperator& A, const Preconditioner& M,
                   const Eigen::Ref<const Eigen::MatrixXd>& B,
                   const Eigen::Ref<const Eigen::MatrixXd>& X) {
  const Eigen::Index n = A.dim();
  if (M.dim() == n && B.rows() == n && X.rows() == n && X.cols() == B.cols() && B.cols() >= 1) {
    return Status::Ok();
  }
  return Status::Error(StatusCode::kInvalidArgument,
                       std::string(where) + ": sizes disagree (operator " + std::to_string(n) +
                           ", preconditioner " + std::to_string(M.dim()) + ", B " +
                           std::to_string(B.rows()) + "x" + std::to_string(B.cols()) + ", X " +
                           std::to_string(X.rows()) + "x" + std::to_string(X.cols()) + ")");
}

/// The summary's residuals from the residual R at exit.
void finish_summary(const Eigen::Ref<const Eigen::MatrixXd>& R, const Eigen::VectorXd& rhs_norm,
                    const PcgOptions& options, PcgSummary& summary) {
  summary.residual_norm = R.colwise().norm().transpose();
  summary.relative_residual.resize(R.cols());
  for (Eigen::Index c = 0; c < R.cols(); ++c) {
    summary.relative_residual[c] = relative(summary.residual_norm[c], rhs_norm[c]);
  }
  summary.max_relative_residual = summary.relative_residual.maxCoeff();
  summary.converged = options.relative_tolerance > 0.0 &&
                      summary.max_relative_residual <= options.relative_tolerance;
}

}  // namespace

void CsrOperator::multiply(const Eigen::Ref<const Eigen::MatrixXd>& X,
                           Eigen::Ref<Eigen::MatrixXd> Y) const {
  // One pass over Λ for all columns: X is copied to row-major so that the m values of row j
  // of X are contiguous and each nonzero updates m accumulators (a column-at-a-time product
  // would stream the whole matrix from memory m times).
  constexpr Eigen::Index kMaxColumns = 16;
  const Eigen::Index n = lambda_.rows();
  const Eigen::Index m = X.cols();
  if (m > kMaxColumns) {
    Y.noalias() = lambda_ * X;
    return;
  }
  thread_local Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> xt, yt;
  xt = X;
  yt.resize(n, m);
  const int* outer = lambda_.outerIndexPtr();
  const int* inner = lambda_.innerIndexPtr();
  const double* values = lambda_.valuePtr();
  const double* x = xt.data();
  double sum[kMaxColumns];
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index c = 0; c < m; ++c) sum[c] = 0.0;
    for (int k = outer[i]; k < outer[i + 1]; ++k) {
      const double v = values[k];
      const double* xj = x + Eigen::Index{inner[k]} * m;
      for (Eigen::Index c = 0; c < m; ++c) sum[c] += v * xj[c];
    }
    double* yi = yt.data() + i * m;
    for (Eigen::Index c = 0; c < m; ++c) yi[c] = sum[c];
  }
  Y = yt;
}

Status BlockJacobiPreconditioner::invert_block(int index,
                                               const Eigen::Ref<const Eigen::MatrixXd>& block) {
  Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (block + block.transpose()));
  if (llt.info() != Eigen::Success) {
    inverse_blocks_.clear();
    return Status::Error(StatusCode::kNotPositiveDefinite,
                         "block-Jacobi preconditioner: diagonal block " + std::to_string(index) +
                             " of the information matrix is not positive definite");
  }
  inverse_blocks_[static_cast<size_t>(index)] =
      llt.solve(Eigen::MatrixXd::Identity(block.rows(), block.cols()));
  return Status::Ok();
}

Status BlockJacobiPreconditioner::factor(const CsrMatrix& lambda, int block_dim) {
  inverse_blocks_.clear();
  if (block_dim < 1 || lambda.rows() != lambda.cols() || lambda.rows() % block_dim != 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "block-Jacobi preconditioner: matrix " + std::to_string(lambda.rows()) +
                             "x" + std::to_string(lambda.cols()) +
                             " is not square with a size multiple of block_dim " +
                             std::to_string(block_dim));
  }
  block_dim_ = block_dim;
  const int blocks = static_cast<int>(lambda.rows() / block_dim);
  inverse_blocks_.resize(static_cast<size_t>(blocks));
  Eigen::MatrixXd diagonal(block_dim, block_dim);
  for (int b = 0; b < blocks; ++b) {
    diagonal.setZero();
    const Eigen::Index first = Eigen::Index{b} * block_dim;
    for (Eigen::Index row = first; row < first + block_dim; ++row) {
      for (CsrMatrix::InnerIterator it(lambda, row); it; ++it) {
        if (it.col() >= first && it.col() < first + block_dim) {
          diagonal(row - first, it.col() - first) = it.value();
        }
      }
    }
    if (Status s = invert_block(b, diagonal); !s.ok()) return s;
  }
  return Status::Ok();
}

Status BlockJacobiPreconditioner::factor(const InformationMatrix& lambda) {
  inverse_blocks_.clear();
  block_dim_ = lambda.block_dim();
  inverse_blocks_.resize(static_cast<size_t>(lambda.num_blocks()));
  for (int b = 0; b < lambda.num_blocks(); ++b) {
    if (Status s = invert_block(b, lambda.diagonal_block(b)); !s.ok()) return s;
  }
  return Status::Ok();
}

void BlockJacobiPreconditioner::apply(const Eigen::Ref<const Eigen::MatrixXd>& R,
                                      Eigen::Ref<Eigen::MatrixXd> Z) const {
  for (int b = 0; b < num_blocks(); ++b) {
    const Eigen::Index first = Eigen::Index{b} * block_dim_;
    Z.middleRows(first, block_dim_).noalias() =
        inverse_blocks_[static_cast<size_t>(b)] * R.middleRows(first, block_dim_);
  }
}

Status PcgOptions::validate() const {
  if (max_iterations < 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "PcgOptions.max_iterations must be >= 0, got " +
                             std::to_string(max_iterations));
  }
  if (!(relative_tolerance >= 0.0) || !std::isfinite(relative_tolerance)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "PcgOptions.relative_tolerance must be finite and >= 0, got " +
                             std::to_string(relative_tolerance));
  }
  return Status::Ok();
}

int restart_worse_than_zero(const Eigen::Ref<const Eigen::MatrixXd>& B,
                            const Eigen::Ref<const Eigen::MatrixXd>& AX,
                            Eigen::Ref<Eigen::MatrixXd> X, Eigen::Ref<Eigen::MatrixXd> R) {
  int restarted = 0;
  for (Eigen::Index c = 0; c < B.cols(); ++c) {
    if (X.col(c).dot(AX.col(c)) - 2.0 * B.col(c).dot(X.col(c)) > 0.0) {
      X.col(c).setZero();
      R.col(c) = B.col(c);
      ++restarted;
    }
  }
  return restarted;
}

bool meets_tolerance(const PcgOptions& options, double residual_norm, double rhs_norm) {
  return options.relative_tolerance > 0.0 && residual_norm <= options.relative_tolerance * rhs_norm;
}

bool refinement_step_raised_error(const Eigen::Ref<const Eigen::VectorXd>& z,
                                  const Eigen::Ref<const Eigen::VectorXd>& r_before,
                                  const Eigen::Ref<const Eigen::VectorXd>& r_after) {
  return z.dot(r_before - r_after) > 2.0 * z.dot(r_before);
}

PcgSummary solve_pcg(const SpdOperator& A, const Preconditioner& M,
                     const Eigen::Ref<const Eigen::MatrixXd>& B, Eigen::Ref<Eigen::MatrixXd> X,
                     const PcgOptions& options, PcgWorkspace& workspace) {
  PcgSummary summary;
  summary.status = options.validate();
  if (!summary.status.ok()) return summary;
  summary.status = check_sizes("solve_pcg", A, M, B, X);
  if (!summary.status.ok()) return summary;
  const Eigen::Index n = A.dim();
  const Eigen::Index m = B.cols();
  auto R = scratch(workspace.R, n, m);
  auto Z = scratch(workspace.Z, n, m);
  auto P = scratch(workspace.P, n, m);
  auto Q = scratch(workspace.Q, n, m);

  // R = B - A X (warm start), Z = M^-1 R, P = Z.
  A.multiply(X, Q);
  R = B - Q;
  const Eigen::VectorXd rhs_norm = B.colwise().norm().transpose();
  if (options.restart_worse_than_zero)
    summary.restarted_columns = restart_worse_than_zero(B, Q, X, R);
  M.apply(R, Z);
  P = Z;

  Eigen::VectorXd rz = (R.cwiseProduct(Z)).colwise().sum().transpose();
  std::vector<bool> active(static_cast<size_t>(m), true);
  auto column_done = [&](Eigen::Index c) {
    return meets_tolerance(options, R.col(c).norm(), rhs_norm[c]);
  };
  int active_count = 0;
  for (Eigen::Index c = 0; c < m; ++c) {
    active[static_cast<size_t>(c)] = !column_done(c);
    active_count += active[static_cast<size_t>(c)] ? 1 : 0;
  }

  int iteration = 0;
  for (; iteration < options.max_iterations && active_count > 0; ++iteration) {
    A.multiply(P, Q);
    for (Eigen::Index c = 0; c < m; ++c) {
      if (!active[static_cast<size_t>(c)]) continue;
      const double pq = P.col(c).dot(Q.col(c));
      if (!(pq > 0.0)) {
        // Breakdown: either the column is already exact (p = 0) or A is not SPD.
        if (P.col(c).squaredNorm() > 0.0 && summary.status.ok()) {
          summary.status = Status::Error(
              StatusCode::kNumericalFailure,
              "solve_pcg: p^T A p = " + std::to_string(pq) + " <= 0 in column " +
                  std::to_string(c) + " at iteration " + std::to_string(iteration) +
                  " (operator not positive definite?)");
        }
        active[static_cast<size_t>(c)] = false;
        --active_count;
        continue;
      }
      const double alpha = rz[c] / pq;
      X.col(c) += alpha * P.col(c);
      R.col(c) -= alpha * Q.col(c);
      if (column_done(c)) {
        active[static_cast<size_t>(c)] = false;
        --active_count;
      }
    }
    // After the last iteration the next direction is never used: skip its preconditioner
    // solve (with a factor M, a full pair of triangular solves).
    if (iteration + 1 >= options.max_iterations || active_count == 0) continue;
    M.apply(R, Z);
    for (Eigen::Index c = 0; c < m; ++c) {
      if (!active[static_cast<size_t>(c)]) continue;
      const double rz_new = R.col(c).dot(Z.col(c));
      const double beta = rz[c] > 0.0 ? rz_new / rz[c] : 0.0;
      rz[c] = rz_new;
      P.col(c) = Z.col(c) + beta * P.col(c);
    }
  }
  summary.iterations = iteration;

  if (options.recompute_true_residual) {
    A.multiply(X, Q);
    R = B - Q;
  }
  finish_summary(R, rhs_norm, options, summary);
  return summary;
}

PcgSummary solve_refinement(const SpdOperator& A, const Preconditioner& M,
                            const Eigen::Ref<const Eigen::MatrixXd>& B,
                            Eigen::Ref<Eigen::MatrixXd> X, const PcgOptions& options,
                            PcgWorkspace& workspace) {
  PcgSummary summary;
  summary.status = options.validate();
  if (summary.status.ok()) summary.status = check_sizes("solve_refinement", A, M, B, X);
  if (!summary.status.ok()) return summary;
  const Eigen::Index n = A.dim();
  const Eigen::Index m = B.cols();
  auto R = scratch(workspace.R, n, m);  // true residual B - A X
  auto Z = scratch(workspace.Z, n, m);  // the step M⁻¹ R
  auto R_before = scratch(workspace.P, n, m);
  auto X_before = scratch(workspace.Q, n, m);

  A.multiply(X, X_before);  // A X, before it holds X
  R = B - X_before;
  if (options.restart_worse_than_zero) {
    summary.restarted_columns = restart_worse_than_zero(B, X_before, X, R);
  }
  const Eigen::VectorXd rhs_norm = B.colwise().norm().transpose();
  std::vector<bool> active(static_cast<size_t>(m));
  int active_count = 0;
  for (Eigen::Index c = 0; c < m; ++c) {
    active[static_cast<size_t>(c)] = !meets_tolerance(options, R.col(c).norm(), rhs_norm[c]);
    active_count += active[static_cast<size_t>(c)] ? 1 : 0;
  }
  int iteration = 0;
  for (; iteration < options.max_iterations && active_count > 0; ++iteration) {
    M.apply(R, Z);
    for (Eigen::Index c = 0; c < m; ++c) {
      if (!active[static_cast<size_t>(c)]) Z.col(c).setZero();
    }
    R_before = R;
    X_before = X;
    X += Z;
    A.multiply(X, R);
    R = B - R;
    for (Eigen::Index c = 0; c < m; ++c) {
      if (!active[static_cast<size_t>(c)]) continue;
      const bool worse = refinement_step_raised_error(Z.col(c), R_before.col(c), R.col(c));
      if (worse) {
        X.col(c) = X_before.col(c);
        R.col(c) = R_before.col(c);
      }
      // Stagnation: a step that did not halve the residual has reached the rounding floor
      // (or M is far from A); more would only spin, up to max_iterations solves.
      const double r_norm = R.col(c).norm();
      const bool stalled = r_norm > 0.5 * R_before.col(c).norm();
      if (worse || stalled || meets_tolerance(options, r_norm, rhs_norm[c])) {
        active[static_cast<size_t>(c)] = false;
        --active_count;
      }
    }
  }
  summary.iterations = iteration;
  finish_summary(R, rhs_norm, options, summary);
  return summary;
}

}  // namespace nav::core
