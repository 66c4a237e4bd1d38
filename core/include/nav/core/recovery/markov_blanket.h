#pragma once
// Markov-blanket (conditional) covariance, the data-association approximation of Thrun et
// al.'s SEIF (IJRR 2004) that Eustice et al. (RSS 2005, Sec. IV and Fig. 3) compare their
// bounds against. For blocks r and i:
//   1. S = {r, i} union the Markov blankets (neighbours in Lambda) of r and of i;
//   2. if the two blankets are disjoint (no common block), add every block of one shortest
//      path from r to i in the block graph of Lambda (breadth-first search), so S is connected;
//   3. Sigma_mb = (Lambda_SS)^-1, the covariance of x_S *conditioned on all other states*
//      being known; return its rows/cols of [r, i].
// Conditioning can only shrink a covariance: Sigma_true[r,i] - Sigma_mb[r,i] is PSD, i.e. the
// Markov-blanket estimate is over-confident (the reason the paper rejects it for data
// association).

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

#include "nav/core/filter/information_matrix.h"

namespace nav::core {

struct MarkovBlanketResult {
  /// 2d x 2d joint [[S_rr S_ri]; [S_ir S_ii]] of the conditional covariance.
  Eigen::MatrixXd joint;
  /// The blocks of S in increasing order (r, i, blankets, path).
  std::vector<int> blocks;
  /// Blocks added by the shortest path (empty when the blankets touch).
  std::vector<int> path_blocks;
};

/// Undirected block adjacency of a symmetric sparse matrix: neighbours[a] = sorted blocks
/// b != a with any nonzero in block (a, b). Lambda's size must be a multiple of block_dim.
std::vector<std::vector<int>> block_adjacency(const Eigen::SparseMatrix<double>& Lambda,
                                              int block_dim);

/// Shortest path r -> i (inclusive) over `adjacency` by breadth-first search; empty if none.
std::vector<int> shortest_block_path(const std::vector<std::vector<int>>& adjacency, int r, int i);

/// The Markov-blanket joint of blocks r != i (see the file comment). Lambda both triangles.
/// Throws std::invalid_argument for r == i or out-of-range blocks, std::runtime_error if
/// Lambda_SS is not positive definite or r and i are not connected.
MarkovBlanketResult markov_blanket_joint(const Eigen::SparseMatrix<double>& Lambda, int block_dim,
                                         int r, int i);
/// Same, on the filter's block-sparse matrix (neighbours read directly).
MarkovBlanketResult markov_blanket_joint(const InformationMatrix& Lambda, int r, int i);

}  // namespace nav::core
