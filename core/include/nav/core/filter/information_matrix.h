#pragma once
// Symmetric block-sparse information matrix Λ of the exactly sparse delayed-state filter
// (Eustice, Singh & Leonard, ICRA 2005; Eustice et al., RSS 2005 Fig. 2). The matrix is a grid
// of square blocks of size block_dim (12 for vehicle states, 6 for pose-only graphs), one
// block row per state. Only the diagonal and the blocks between states linked by a motion
// or measurement constraint are stored, so an update touches only the blocks involved.
//
// Storage: each block row owns its diagonal block and a short list of off-diagonal blocks
// (neighbour index, block). BOTH halves are stored: block (i, j) lives in row i and its
// transpose (j, i) in row j, and the two are always kept equal (Λ_ji = Λ_ijᵀ). Rows live in a
// std::deque, so appending a state never moves existing rows (no O(n) reallocation).
// Blocks are fixed-capacity 12x12 Eigen matrices: no heap allocation per block.
//
// Not thread-safe; the filter thread is the only writer (docs/architecture.md).

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

namespace nav::core {

class InformationMatrix {
 public:
  /// One block: block_dim x block_dim, stored inline (at most 12 x 12, no heap).
  using Block = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, 12, 12>;
  static constexpr int kMaxBlockDim = 12;

  /// block_dim must be in [1, 12] (6 or 12 in practice); throws std::invalid_argument
  /// otherwise (a programming error, not a runtime input).
  explicit InformationMatrix(int block_dim);

  int block_dim() const { return block_dim_; }
  int num_blocks() const { return static_cast<int>(rows_.size()); }
  /// Scalar dimension, num_blocks() * block_dim().
  Eigen::Index dim() const { return Eigen::Index{num_blocks()} * block_dim_; }

  /// Appends a block row/column of zeros; returns its index (== old num_blocks()).
  int add_block();

  /// Λ_ij += m and, for i != j, Λ_ji += mᵀ (creating the blocks if needed). For i == j, m is
  /// symmetrised first (Λ_ii += (m + mᵀ)/2). m must be block_dim x block_dim; indices must be
  /// valid (checked with assert only: the filter validates its inputs).
  void add_to_block(int i, int j, const Eigen::Ref<const Eigen::MatrixXd>& m);

  /// Λ_ij as a dense block_dim x block_dim matrix (zero if not stored).
  Eigen::MatrixXd block(int i, int j) const;
  /// Pointer to the stored block Λ_ij (i != j allowed), nullptr if not stored. Valid until the
  /// next non-const call.
  const Block* find_block(int i, int j) const;

  const Block& diagonal_block(int i) const { return rows_[static_cast<size_t>(i)].diagonal; }

  /// Indices j != i with a stored block (i, j), in storage order (not sorted).
  std::vector<int> neighbours(int i) const;
  /// Number of neighbours of row i (no allocation).
  int num_neighbours(int i) const;
  /// The k-th neighbour of row i and its block Λ_{i,nbr}; k < num_neighbours(i).
  int neighbour(int i, int k) const;
  const Block& neighbour_block(int i, int k) const;

  /// Removes every block (i, *) and (*, i); the diagonal block becomes zero. The row stays.
  void clear_row(int i);

  /// Relabels states a and b (a symmetric permutation of block rows and columns): afterwards
  /// block (a, j) holds what was (b, π(j)) with π swapping a and b. O(neighbours of a and b).
  void swap_rows(int a, int b);

  /// Y = Λ X for X of dim() rows and any number of columns; Y must have the same shape.
  void multiply(const Eigen::Ref<const Eigen::MatrixXd>& X, Eigen::Ref<Eigen::MatrixXd> Y) const;

  /// Full symmetric matrix (both triangles), column-major, compressed.
  Eigen::SparseMatrix<double> to_sparse() const;
  /// Dense copy, for small tests only.
  Eigen::MatrixXd to_dense() const;

  /// Number of stored off-diagonal block pairs {i, j}, i < j.
  size_t num_off_diagonal_pairs() const { return num_pairs_; }

  /// Running count of stored blocks modified (written, created, removed or relabelled; the two
  /// halves of a pair count as two). The filter differences it to report how many blocks an
  /// operation touched (the constant-time property of the ESDF).
  size_t blocks_written() const { return blocks_written_; }

  /// Both ways: the blocks-written counter and the `num_rows` block rows (diagonal, neighbour
  /// count, neighbours in storage order); reading replaces the matrix and checks the neighbour
  /// lists and that the two stored halves are exact transposes
  /// (core/serialization/map_serialization.h).
  template <class Archive>
  void serialize(Archive& ar, std::uint32_t num_rows);

 private:
  struct Entry {
    int col;
    Block block;
  };
  struct Row {
    Block diagonal;
    std::vector<Entry> off;  // one entry per neighbour
  };

  Block* find_mutable(int i, int j);
  Block& find_or_insert(int i, int j);
  void relabel(int row, int from, int to);

  int block_dim_;
  std::deque<Row> rows_;
  size_t num_pairs_ = 0;
  size_t blocks_written_ = 0;
};

}  // namespace nav::core
