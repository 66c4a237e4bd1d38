// Markov-blanket conditional covariance (recovery/markov_blanket.h; Thrun et al., SEIF,
// IJRR 2004; the comparison of Eustice et al., RSS 2005, Fig. 3).

#include "nav/core/recovery/markov_blanket.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <deque>
#include <stdexcept>
#include <string>

namespace nav::core {

namespace {

using Adjacency = std::vector<std::vector<int>>;

void check_blocks(int r, int i, int num_blocks) {
  if (r < 0 || i < 0 || r >= num_blocks || i >= num_blocks) {
    throw std::invalid_argument("markov_blanket_joint: blocks (" + std::to_string(r) + ", " +
                                std::to_string(i) + ") outside [0, " + std::to_string(num_blocks) +
                                ")");
  }
  if (r == i) {
    throw std::invalid_argument("markov_blanket_joint: r and i are the same block " +
                                std::to_string(r));
  }
}

/// The block set S of the header's steps 1-2, sorted, and the path blocks.
void select_blocks(const Adjacency& adjacency, int r, int i, MarkovBlanketResult& out) {
  std::vector<int> blanket_r = adjacency[static_cast<size_t>(r)];
  blanket_r.push_back(r);
  std::vector<int> blanket_i = adjacency[static_cast<size_t>(i)];
  blanket_i.push_back(i);
  std::sort(blanket_r.begin(), blanket_r.end());
  std::sort(blanket_i.begin(), blanket_i.end());
  std::vector<int> common;
  std::set_intersection(blanket_r.begin(), blanket_r.end(), blanket_i.begin(), blanket_i.end(),
                        std::back_inserter(common));
  std::vector<int> S;
  std::set_union(blanket_r.begin(), blanket_r.end(), blanket_i.begin(), blanket_i.end(),
                 std::back_inserter(S));
  if (common.empty()) {
    const std::vector<int> path = shortest_block_path(adjacency, r, i);
    if (path.empty()) {
      throw std::runtime_error("markov_blanket_joint: blocks " + std::to_string(r) + " and " +
                               std::to_string(i) + " are not connected in the information graph");
    }
    for (int b : path) {
      if (!std::binary_search(S.begin(), S.end(), b)) out.path_blocks.push_back(b);
    }
    S.insert(S.end(), out.path_blocks.begin(), out.path_blocks.end());
    std::sort(S.begin(), S.end());
  }
  out.blocks = S;
}

/// Inverts Lambda_SS (dense, |S| d) and extracts the [r, i] joint.
template <typename BlockFn>
void conditional_joint(const BlockFn& block, int d, int r, int i, MarkovBlanketResult& out) {
  const std::vector<int>& S = out.blocks;
  const Eigen::Index m = static_cast<Eigen::Index>(S.size()) * d;
  Eigen::MatrixXd sub(m, m);
  for (size_t a = 0; a < S.size(); ++a) {
    for (size_t b = 0; b < S.size(); ++b) {
      sub.block(static_cast<Eigen::Index>(a) * d, static_cast<Eigen::Index>(b) * d, d, d) =
          block(S[a], S[b]);
    }
  }
  Eigen::LLT<Eigen::MatrixXd> llt(sub);
  if (llt.info() != Eigen::Success) {
    throw std::runtime_error("markov_blanket_joint: the information sub-block of " +
                             std::to_string(S.size()) + " blocks is not positive definite");
  }
  const auto pos = [&](int b) {
    return static_cast<Eigen::Index>(std::lower_bound(S.begin(), S.end(), b) - S.begin()) * d;
  };
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(m, 2 * d);
  E.block(pos(r), 0, d, d).setIdentity();
  E.block(pos(i), d, d, d).setIdentity();
  const Eigen::MatrixXd X = llt.solve(E);
  out.joint.resize(2 * d, 2 * d);
  out.joint.topRows(d) = X.middleRows(pos(r), d);
  out.joint.bottomRows(d) = X.middleRows(pos(i), d);
  out.joint = 0.5 * (out.joint + out.joint.transpose()).eval();
}

}  // namespace

std::vector<std::vector<int>> block_adjacency(const Eigen::SparseMatrix<double>& Lambda,
                                              int block_dim) {
  if (block_dim < 1 || Lambda.rows() != Lambda.cols() || Lambda.rows() % block_dim != 0) {
    throw std::invalid_argument("block_adjacency: matrix " + std::to_string(Lambda.rows()) + "x" +
                                std::to_string(Lambda.cols()) +
                                " is not square or not a multiple "
                                "of block_dim " +
                                std::to_string(block_dim));
  }
  const Eigen::Index nb = Lambda.rows() / block_dim;
  Adjacency adjacency(static_cast<size_t>(nb));
  for (Eigen::Index j = 0; j < Lambda.outerSize(); ++j) {
    const int bj = static_cast<int>(j / block_dim);
    for (Eigen::SparseMatrix<double>::InnerIterator it(Lambda, j); it; ++it) {
      const int bi = static_cast<int>(it.row() / block_dim);
      if (bi != bj && it.value() != 0.0) {
        adjacency[static_cast<size_t>(bi)].push_back(bj);
        adjacency[static_cast<size_t>(bj)].push_back(bi);
      }
    }
  }
  for (auto& nbrs : adjacency) {
    std::sort(nbrs.begin(), nbrs.end());
    nbrs.erase(std::unique(nbrs.begin(), nbrs.end()), nbrs.end());
  }
  return adjacency;
}

std::vector<int> shortest_block_path(const std::vector<std::vector<int>>& adjacency, int r, int i) {
  std::vector<int> parent(adjacency.size(), -1);
  std::deque<int> queue{r};
  parent[static_cast<size_t>(r)] = r;
  while (!queue.empty() && parent[static_cast<size_t>(i)] < 0) {
    const int a = queue.front();
    queue.pop_front();
    for (int b : adjacency[static_cast<size_t>(a)]) {
      if (parent[static_cast<size_t>(b)] < 0) {
        parent[static_cast<size_t>(b)] = a;
        queue.push_back(b);
      }
    }
  }
  if (parent[static_cast<size_t>(i)] < 0) return {};
  std::vector<int> path{i};
  while (path.back() != r) path.push_back(parent[static_cast<size_t>(path.back())]);
  std::reverse(path.begin(), path.end());
  return path;
}

MarkovBlanketResult markov_blanket_joint(const Eigen::SparseMatrix<double>& Lambda, int block_dim,
                                         int r, int i) {
  const Adjacency adjacency = block_adjacency(Lambda, block_dim);
  check_blocks(r, i, static_cast<int>(adjacency.size()));
  MarkovBlanketResult out;
  select_blocks(adjacency, r, i, out);
  const auto block = [&](int a, int b) -> Eigen::MatrixXd {
    return Eigen::MatrixXd(Lambda.block(Eigen::Index{a} * block_dim, Eigen::Index{b} * block_dim,
                                        block_dim, block_dim));
  };
  conditional_joint(block, block_dim, r, i, out);
  return out;
}

MarkovBlanketResult markov_blanket_joint(const InformationMatrix& Lambda, int r, int i) {
  check_blocks(r, i, Lambda.num_blocks());
  Adjacency adjacency(static_cast<size_t>(Lambda.num_blocks()));
  for (int b = 0; b < Lambda.num_blocks(); ++b) {
    adjacency[static_cast<size_t>(b)] = Lambda.neighbours(b);
    std::sort(adjacency[static_cast<size_t>(b)].begin(), adjacency[static_cast<size_t>(b)].end());
  }
  MarkovBlanketResult out;
  select_blocks(adjacency, r, i, out);
  const auto block = [&](int a, int b) { return Lambda.block(a, b); };
  conditional_joint(block, Lambda.block_dim(), r, i, out);
  return out;
}

}  // namespace nav::core
