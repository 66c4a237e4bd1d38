// Λμ kept between recovery steps (recovery/mean_product.h): after a link between two states, an
// appended state and a moved robot mean, recomputing only the changed rows, the moved blocks
// and their neighbours gives the full product; a stale base or unknown changed rows give none.
#include "nav/core/recovery/mean_product.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

namespace nav::core {
namespace {

constexpr int kD = 6;

Eigen::MatrixXd random_block(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::MatrixXd m(kD, kD);
  for (int i = 0; i < m.size(); ++i) m(i) = normal(rng);
  return m;
}

/// A chain of `blocks` (>= 12) states with a few longer couplings; the robot (block 0) coupled to
/// the newest state and to block 5.
InformationMatrix chain(int blocks, std::mt19937& rng) {
  InformationMatrix lambda(kD);
  for (int b = 0; b < blocks; ++b) lambda.add_block();
  for (int b = 0; b < blocks; ++b) {
    const Eigen::MatrixXd m = random_block(rng);
    lambda.add_to_block(b, b, m * m.transpose() + 10.0 * Eigen::MatrixXd::Identity(kD, kD));
  }
  for (int b = 2; b < blocks; ++b) lambda.add_to_block(b - 1, b, random_block(rng));
  lambda.add_to_block(0, blocks - 1, random_block(rng));
  lambda.add_to_block(0, 5, random_block(rng));
  lambda.add_to_block(3, 11, random_block(rng));
  return lambda;
}

Eigen::VectorXd full_product(const InformationMatrix& lambda, const Eigen::VectorXd& mean) {
  Eigen::VectorXd y(lambda.dim());
  lambda.multiply(mean, y);
  return y;
}

TEST(MeanProduct, RecomputesTheChangedRowsAndTheNeighboursOfMovedMeans) {
  std::mt19937 rng(11);
  InformationMatrix lambda = chain(16, rng);
  Eigen::VectorXd mean = Eigen::VectorXd::Random(lambda.dim());
  MeanProduct product;
  product.set(full_product(lambda, mean), 1);
  // A link between states 7 and 12 (their rows change), a state appended and coupled to the
  // robot, and the robot's mean moved (its neighbours' rows change with it).
  lambda.add_to_block(7, 12, random_block(rng));
  lambda.add_to_block(7, 7, 0.1 * Eigen::MatrixXd::Identity(kD, kD));
  lambda.add_to_block(12, 12, 0.1 * Eigen::MatrixXd::Identity(kD, kD));
  const int appended = lambda.add_block();
  lambda.add_to_block(appended, appended, 10.0 * Eigen::MatrixXd::Identity(kD, kD));
  lambda.add_to_block(0, appended, random_block(rng));
  mean.conservativeResize(lambda.dim());
  mean.tail(kD).setRandom();
  mean.head(kD).setRandom();
  product.moved(0);
  product.moved(appended);
  const std::vector<int> changed = {0, 7, 12, appended};
  Eigen::VectorXd out = Eigen::VectorXd::Zero(lambda.dim());
  const int rows = product.update(lambda, &changed, mean, 2, out);
  const Eigen::VectorXd expected = full_product(lambda, mean);
  EXPECT_LT((out - expected).norm(), 1e-12 * expected.norm());
  // 0, 7, 12, the appended state and the robot's neighbours 5 and 15: 6 of 17 rows.
  EXPECT_EQ(rows, 6);
}

TEST(MeanProduct, GivesNothingFromAStaleBaseOrUnknownChanges) {
  std::mt19937 rng(5);
  const InformationMatrix lambda = chain(16, rng);
  const Eigen::VectorXd mean = Eigen::VectorXd::Random(lambda.dim());
  const std::vector<int> none;
  Eigen::VectorXd out = Eigen::VectorXd::Constant(lambda.dim(), 7.0);
  MeanProduct product;
  EXPECT_EQ(product.update(lambda, &none, mean, 1, out), -1);  // no base yet
  product.set(full_product(lambda, mean), 1);
  EXPECT_EQ(product.update(lambda, &none, mean, 3, out), -1);  // a solve went between
  product.set(full_product(lambda, mean), 3);
  EXPECT_EQ(product.update(lambda, nullptr, mean, 4, out), -1);  // changes unknown
  EXPECT_TRUE((out.array() == 7.0).all());
  product.set(full_product(lambda, mean), 4);
  product.invalidate();
  EXPECT_EQ(product.update(lambda, &none, mean, 5, out), -1);
  product.set(full_product(lambda, mean), 5);
  EXPECT_EQ(product.update(lambda, &none, mean, 6, out), 0);  // nothing changed, nothing due
  EXPECT_LT((out - full_product(lambda, mean)).norm(), 1e-12);
  EXPECT_EQ(product.update(lambda, &none, mean, 7, out), -1);  // a base serves one step
}

}  // namespace
}  // namespace nav::core
