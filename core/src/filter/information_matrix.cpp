// Block-sparse symmetric information matrix (see information_matrix.h for the storage layout).
#include "nav/core/filter/information_matrix.h"

#include <algorithm>
#include <cassert>
#include <stdexcept>
#include <string>

namespace nav::core {

InformationMatrix::InformationMatrix(int block_dim) : block_dim_(block_dim) {
  if (block_dim < 1 || block_dim > kMaxBlockDim) {
    throw std::invalid_argument("InformationMatrix: block_dim " + std::to_string(block_dim) +
                                " outside [1, 12]");
  }
}

int InformationMatrix::add_block() {
  Row& row = rows_.emplace_back();
  row.diagonal.setZero(block_dim_, block_dim_);
  return num_blocks() - 1;
}

InformationMatrix::Block* InformationMatrix::find_mutable(int i, int j) {
  Row& row = rows_[static_cast<size_t>(i)];
  if (i == j) return &row.diagonal;
  for (Entry& e : row.off) {
    if (e.col == j) return &e.block;
  }
  return nullptr;
}

const InformationMatrix::Block* InformationMatrix::find_block(int i, int j) const {
  return const_cast<InformationMatrix*>(this)->find_mutable(i, j);
}

InformationMatrix::Block& InformationMatrix::find_or_insert(int i, int j) {
  if (Block* b = find_mutable(i, j)) return *b;
  Entry& e = rows_[static_cast<size_t>(i)].off.emplace_back();
  e.col = j;
  e.block.setZero(block_dim_, block_dim_);
  return e.block;
}

void InformationMatrix::add_to_block(int i, int j, const Eigen::Ref<const Eigen::MatrixXd>& m) {
  assert(i >= 0 && i < num_blocks() && j >= 0 && j < num_blocks());
  assert(m.rows() == block_dim_ && m.cols() == block_dim_);
  if (i == j) {
    rows_[static_cast<size_t>(i)].diagonal += 0.5 * (m + m.transpose());
    ++blocks_written_;
    return;
  }
  const bool existed = find_mutable(i, j) != nullptr;
  find_or_insert(i, j) += m;
  find_or_insert(j, i) += m.transpose();
  if (!existed) ++num_pairs_;
  blocks_written_ += 2;
}

Eigen::MatrixXd InformationMatrix::block(int i, int j) const {
  if (const Block* b = find_block(i, j)) return *b;
  return Eigen::MatrixXd::Zero(block_dim_, block_dim_);
}

std::vector<int> InformationMatrix::neighbours(int i) const {
  std::vector<int> out;
  const Row& row = rows_[static_cast<size_t>(i)];
  out.reserve(row.off.size());
  for (const Entry& e : row.off) out.push_back(e.col);
  return out;
}

int InformationMatrix::num_neighbours(int i) const {
  return static_cast<int>(rows_[static_cast<size_t>(i)].off.size());
}

int InformationMatrix::neighbour(int i, int k) const {
  return rows_[static_cast<size_t>(i)].off[static_cast<size_t>(k)].col;
}

const InformationMatrix::Block& InformationMatrix::neighbour_block(int i, int k) const {
  return rows_[static_cast<size_t>(i)].off[static_cast<size_t>(k)].block;
}

void InformationMatrix::clear_row(int i) {
  Row& row = rows_[static_cast<size_t>(i)];
  for (const Entry& e : row.off) {
    auto& other = rows_[static_cast<size_t>(e.col)].off;
    auto it = std::find_if(other.begin(), other.end(), [i](const Entry& x) { return x.col == i; });
    assert(it != other.end());
    if (it != other.end()) {
      *it = std::move(other.back());
      other.pop_back();
    }
    --num_pairs_;
    blocks_written_ += 2;
  }
  row.off.clear();
  ++blocks_written_;
  row.diagonal.setZero(block_dim_, block_dim_);
}

void InformationMatrix::relabel(int row, int from, int to) {
  for (Entry& e : rows_[static_cast<size_t>(row)].off) {
    if (e.col == from) {
      e.col = to;
      ++blocks_written_;
    } else if (e.col == to) {
      e.col = from;
      ++blocks_written_;
    }
  }
}

void InformationMatrix::swap_rows(int a, int b) {
  if (a == b) return;
  // Rows other than a and b that refer to a or b: swap the labels there once.
  std::vector<int> others;
  for (int r : {a, b}) {
    for (const Entry& e : rows_[static_cast<size_t>(r)].off) {
      if (e.col != a && e.col != b &&
          std::find(others.begin(), others.end(), e.col) == others.end()) {
        others.push_back(e.col);
      }
    }
  }
  for (int r : others) relabel(r, a, b);
  std::swap(rows_[static_cast<size_t>(a)], rows_[static_cast<size_t>(b)]);
  blocks_written_ += 2;
  relabel(a, a, b);
  relabel(b, a, b);
}

void InformationMatrix::multiply(const Eigen::Ref<const Eigen::MatrixXd>& X,
                                 Eigen::Ref<Eigen::MatrixXd> Y) const {
  assert(X.rows() == dim() && Y.rows() == dim() && X.cols() == Y.cols());
  const int d = block_dim_;
  for (int i = 0; i < num_blocks(); ++i) {
    const Row& row = rows_[static_cast<size_t>(i)];
    auto yi = Y.middleRows(Eigen::Index{i} * d, d);
    yi.noalias() = row.diagonal * X.middleRows(Eigen::Index{i} * d, d);
    for (const Entry& e : row.off) {
      yi.noalias() += e.block * X.middleRows(Eigen::Index{e.col} * d, d);
    }
  }
}

Eigen::SparseMatrix<double> InformationMatrix::to_sparse() const {
  const int d = block_dim_;
  const Eigen::Index n = dim();
  Eigen::SparseMatrix<double> S(n, n);
  if (n == 0) return S;  // Eigen's reserve/makeCompressed read past an empty size vector
  // Column c of block column j holds, for every stored block (i, j), the column of Λ_ij; since
  // both halves are stored, row j's entries (j, i) give Λ_ij = Λ_jiᵀ.
  Eigen::VectorXi nnz_per_col(n);
  for (int j = 0; j < num_blocks(); ++j) {
    const int nb = 1 + static_cast<int>(rows_[static_cast<size_t>(j)].off.size());
    nnz_per_col.segment(Eigen::Index{j} * d, d).setConstant(nb * d);
  }
  S.reserve(nnz_per_col);
  std::vector<std::pair<int, const Block*>> blocks;  // (row block i, Λ_ji) sorted by i
  for (int j = 0; j < num_blocks(); ++j) {
    const Row& row = rows_[static_cast<size_t>(j)];
    blocks.clear();
    blocks.emplace_back(j, &row.diagonal);
    for (const Entry& e : row.off) blocks.emplace_back(e.col, &e.block);
    std::sort(blocks.begin(), blocks.end());
    for (int c = 0; c < d; ++c) {
      const Eigen::Index col = Eigen::Index{j} * d + c;
      for (const auto& [i, blk] : blocks) {
        // Λ(i*d + r, j*d + c) = Λ_ij(r, c) = Λ_ji(c, r)
        for (int r = 0; r < d; ++r) {
          S.insert(Eigen::Index{i} * d + r, col) = (*blk)(c, r);
        }
      }
    }
  }
  S.makeCompressed();
  return S;
}

Eigen::MatrixXd InformationMatrix::to_dense() const {
  const int d = block_dim_;
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(dim(), dim());
  for (int i = 0; i < num_blocks(); ++i) {
    const Row& row = rows_[static_cast<size_t>(i)];
    D.block(Eigen::Index{i} * d, Eigen::Index{i} * d, d, d) = row.diagonal;
    for (const Entry& e : row.off) {
      D.block(Eigen::Index{i} * d, Eigen::Index{e.col} * d, d, d) = e.block;
    }
  }
  return D;
}

}  // namespace nav::core
