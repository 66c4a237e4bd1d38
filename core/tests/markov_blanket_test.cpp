// Markov-blanket conditional covariance (recovery/markov_blanket.h).

#include "nav/core/recovery/markov_blanket.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <utility>
#include <vector>

#include "nav/core/posegraph/g2o.h"
#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/testing/data.h"
#include "nav/testing/numeric_jacobian.h"

namespace nav::core {
namespace {

using nav::testing::max_abs_diff;

Eigen::SparseMatrix<double> sparse_of(const Eigen::MatrixXd& m) { return m.sparseView(); }

/// Scalar (d = 1) graph: chain 0-1-2-3-4-5-6 plus a branch 7 hanging on 3.
Eigen::MatrixXd chain_with_branch() {
  Eigen::MatrixXd L = Eigen::MatrixXd::Zero(8, 8);
  const std::vector<std::pair<int, int>> links{{0, 1}, {1, 2}, {2, 3}, {3, 4},
                                               {4, 5}, {5, 6}, {3, 7}};
  for (const auto& [a, b] : links) {
    L(a, b) = L(b, a) = -1.0;
  }
  for (int k = 0; k < 8; ++k) L(k, k) = 3.0 + 0.1 * k;
  return L;
}

TEST(MarkovBlanket, AdjacentBlocksUseTheUnionOfBlanketsByHand) {
  const Eigen::MatrixXd L = chain_with_branch();
  // r = 1, i = 2: blankets {0,1,2} and {1,2,3} -> S = {0,1,2,3}; no path needed.
  const MarkovBlanketResult mb = markov_blanket_joint(sparse_of(L), 1, 1, 2);
  EXPECT_EQ(mb.blocks, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_TRUE(mb.path_blocks.empty());
  Eigen::Matrix4d sub;
  sub << 3.0, -1.0, 0.0, 0.0,  //
      -1.0, 3.1, -1.0, 0.0,    //
      0.0, -1.0, 3.2, -1.0,    //
      0.0, 0.0, -1.0, 3.3;
  const Eigen::Matrix4d inv = sub.inverse();
  Eigen::Matrix2d expected;
  expected << inv(1, 1), inv(1, 2), inv(2, 1), inv(2, 2);
  EXPECT_LT(max_abs_diff(mb.joint, expected), 1e-14);
}

TEST(MarkovBlanket, DisjointBlanketsAddTheShortestPath) {
  const Eigen::MatrixXd L = chain_with_branch();
  // r = 0 {0,1}, i = 5 {4,5,6}: disjoint, shortest path 0-1-2-3-4-5 adds 2 and 3 (not 7).
  const MarkovBlanketResult mb = markov_blanket_joint(sparse_of(L), 1, 0, 5);
  EXPECT_EQ(mb.path_blocks, (std::vector<int>{2, 3}));
  EXPECT_EQ(mb.blocks, (std::vector<int>{0, 1, 2, 3, 4, 5, 6}));
  const Eigen::MatrixXd inv = L.topLeftCorner(7, 7).inverse();
  Eigen::Matrix2d expected;
  expected << inv(0, 0), inv(0, 5), inv(5, 0), inv(5, 5);
  EXPECT_LT(max_abs_diff(mb.joint, expected), 1e-14);
  // Conditioning on x7 removes its variance contribution: strictly smaller than the truth.
  const Eigen::MatrixXd truth = L.inverse();
  Eigen::Matrix2d true_joint;
  true_joint << truth(0, 0), truth(0, 5), truth(5, 0), truth(5, 5);
  double min_eig = 0.0;
  EXPECT_TRUE(is_conservative(true_joint, mb.joint, 1e-12, &min_eig));
  EXPECT_FALSE(is_conservative(mb.joint, true_joint, 1e-9)) << "expected over-confidence";
}

TEST(MarkovBlanket, ShortestPathAndAdjacency) {
  const auto adj = block_adjacency(sparse_of(chain_with_branch()), 1);
  EXPECT_EQ(adj[3], (std::vector<int>{2, 4, 7}));
  EXPECT_EQ(shortest_block_path(adj, 7, 0), (std::vector<int>{7, 3, 2, 1, 0}));
  EXPECT_EQ(shortest_block_path(adj, 4, 4), (std::vector<int>{4}));
  Eigen::MatrixXd two = Eigen::MatrixXd::Identity(2, 2);
  EXPECT_TRUE(shortest_block_path(block_adjacency(sparse_of(two), 1), 0, 1).empty());
  EXPECT_THROW(markov_blanket_joint(sparse_of(two), 1, 0, 1), std::runtime_error);
  EXPECT_THROW(markov_blanket_joint(sparse_of(two), 1, 0, 0), std::invalid_argument);
  EXPECT_THROW(markov_blanket_joint(sparse_of(two), 1, 0, 2), std::invalid_argument);
}

TEST(MarkovBlanket, PoseGraphIsOverConfidentAgainstExactMarginals) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  const PoseGraph g = read_g2o(path.string());
  const auto Lambda = assemble_information_sparse(g);
  const InformationMatrix blocks = assemble_information(g);
  const ExactMarginals em = ExactMarginals::compute(Lambda, 6);
  int strictly_smaller = 0;
  for (const auto& [r, i] : std::vector<std::pair<int, int>>{
           {124, 0}, {124, 123}, {60, 61}, {10, 100}, {0, 1}, {37, 88}}) {
    const MarkovBlanketResult mb = markov_blanket_joint(Lambda, 6, r, i);
    const MarkovBlanketResult mb_blocks = markov_blanket_joint(blocks, r, i);
    EXPECT_EQ(mb.blocks, mb_blocks.blocks);
    EXPECT_LT(max_abs_diff(mb.joint, mb_blocks.joint), 1e-9 * mb.joint.cwiseAbs().maxCoeff());
    const Eigen::MatrixXd truth = em.joint(r, i);
    double min_eig = 0.0;
    EXPECT_TRUE(is_conservative(truth, mb.joint, 1e-9, &min_eig))
        << "pair " << r << ", " << i << ": min eig of truth - mb " << min_eig;
    if (logdet_ratio(mb.joint, truth) < -1.0) ++strictly_smaller;
  }
  // The paper's point: conditioning on the rest of the map shrinks the covariance a lot.
  EXPECT_GE(strictly_smaller, 4);
}

}  // namespace
}  // namespace nav::core
