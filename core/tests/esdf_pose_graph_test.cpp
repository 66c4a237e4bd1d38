// Acceptance test 6: the same Esdf class on 6-element pose-only blocks. A small pose graph
// built by odometry predictions (some intermediate poses marginalised) and RelativePose6Model
// loop closures must equal the dense least-squares information matrix and vector of all
// factors linearised at the same points, with the marginalised poses Schur-complemented out.
#include "nav/core/filter/esdf.h"
#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"
#include "nav/core/models/binary_models.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <map>
#include <random>

namespace nav::core {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

struct Factor {
  int a, b;  // pose indices
  Vec6 z;
  Mat6 Sigma;
};

TEST(EsdfPoseGraph, EqualsDenseLeastSquaresInformation) {
  constexpr int kPoses = 13;  // poses 0..12
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01(0.0, 1.0);
  Vec6 sig_odo;
  sig_odo << 0.05, 0.05, 0.02, 0.01, 0.01, 0.02;
  const Mat6 S_odo = sig_odo.cwiseAbs2().asDiagonal();
  Vec6 x0;
  x0 << 1.0, -2.0, 5.0, 0.02, -0.01, -1.0;
  Vec6 sig0;
  sig0 << 0.1, 0.1, 0.1, 0.01, 0.01, 0.01;
  const Mat6 P0 = sig0.cwiseAbs2().asDiagonal();

  Esdf esdf(6);
  ASSERT_TRUE(esdf.initialize(x0, P0).ok());
  std::vector<Vec6> truth{x0}, lin{x0};  // true poses, ESDF linearisation point of each pose
  std::vector<Factor> factors;
  std::map<int, int> block_of;  // kept pose -> ESDF block
  auto marginalised = [](int p) { return p % 3 == 1 && p != kPoses - 1; };
  const std::vector<std::pair<int, int>> closures{{0, 9}, {2, 8}, {3, 11}, {5, 12}};
  const RelativePose6Model rel;
  Vec6 sig_lc;
  sig_lc << 0.1, 0.1, 0.05, 0.02, 0.02, 0.02;
  const Mat6 S_lc = sig_lc.cwiseAbs2().asDiagonal();

  for (int p = 1; p < kPoses; ++p) {
    Vec6 u;
    u << 1.0, 0.2, 0.05, 0.03, -0.02, 0.18;
    truth.push_back(head_to_tail(truth.back(), u));
    // Odometry measured with noise; the filter predicts the new pose through it.
    Vec6 u_meas = u;
    for (int k = 0; k < 6; ++k) u_meas[k] += sig_odo[k] * n01(rng);
    Mat6x12 J;
    const Vec6 mu = esdf.mean_block(0);
    const Vec6 f = head_to_tail(mu, u_meas, &J);
    const Mat6 F = J.leftCols<6>();
    const Mat6 Q = J.rightCols<6>() * S_odo * J.rightCols<6>().transpose();
    const bool keep = !marginalised(p - 1);
    int kept = -1;
    ASSERT_TRUE(esdf.predict(f, F, Q, keep, &kept).ok());
    if (keep) block_of[p - 1] = kept;
    lin.push_back(f);
    factors.push_back({p - 1, p, u_meas, S_odo});
    for (const auto& [a, b] : closures) {
      if (b != p) continue;
      Vec6 z = tail_to_tail(truth[static_cast<size_t>(a)], truth[static_cast<size_t>(b)]);
      for (int k = 0; k < 6; ++k) z[k] += sig_lc[k] * n01(rng);
      ASSERT_TRUE(esdf.update(rel, block_of.at(a), Esdf::kRobotBlock, z, S_lc).ok());
      factors.push_back({a, b, z, S_lc});
    }
  }
  block_of[kPoses - 1] = Esdf::kRobotBlock;
  ASSERT_EQ(esdf.num_blocks(), static_cast<int>(block_of.size()));

  // Dense least squares over all poses: prior + every factor, Jacobians at `lin`.
  const int N = 6 * kPoses;
  MatrixXd L = MatrixXd::Zero(N, N);
  VectorXd eta = VectorXd::Zero(N);
  const Mat6 P0i = P0.inverse();
  L.topLeftCorner<6, 6>() += P0i;
  eta.head<6>() += P0i * x0;
  for (const Factor& fa : factors) {
    MeasJac Ha, Hb;
    const Vec6 la = lin[static_cast<size_t>(fa.a)], lb = lin[static_cast<size_t>(fa.b)];
    const MeasVec h = rel.predict(la, lb, &Ha, &Hb);
    Vec6 nu = fa.z - Vec6(h);
    for (int k = 3; k < 6; ++k) nu[k] = wrap_angle(nu[k]);
    Eigen::Matrix<double, 6, 12> H;
    H << Ha, Hb;
    Eigen::Matrix<double, 12, 1> mu;
    mu << la, lb;
    const Mat6 Si = fa.Sigma.inverse();
    const Eigen::Matrix<double, 12, 12> HtSiH = H.transpose() * Si * H;
    const Eigen::Matrix<double, 12, 1> g = H.transpose() * Si * (nu + H * mu);
    const int ia = 6 * fa.a, ib = 6 * fa.b;
    L.block<6, 6>(ia, ia) += HtSiH.topLeftCorner<6, 6>();
    L.block<6, 6>(ia, ib) += HtSiH.topRightCorner<6, 6>();
    L.block<6, 6>(ib, ia) += HtSiH.bottomLeftCorner<6, 6>();
    L.block<6, 6>(ib, ib) += HtSiH.bottomRightCorner<6, 6>();
    eta.segment<6>(ia) += g.head<6>();
    eta.segment<6>(ib) += g.tail<6>();
  }
  // Schur complement of the marginalised poses; kept poses in ESDF block order.
  std::vector<int> marg_idx;
  std::vector<int> kept_rows(static_cast<size_t>(esdf.num_blocks()) * 6);
  for (const auto& [pose, block] : block_of) {
    for (int k = 0; k < 6; ++k) kept_rows[static_cast<size_t>(6 * block + k)] = 6 * pose + k;
  }
  for (int p = 0; p < kPoses; ++p) {
    if (block_of.count(p) == 0) {
      for (int k = 0; k < 6; ++k) marg_idx.push_back(6 * p + k);
    }
  }
  const auto nk = static_cast<Eigen::Index>(kept_rows.size());
  const auto nm = static_cast<Eigen::Index>(marg_idx.size());
  ASSERT_GT(nm, 0);
  const MatrixXd Lkk = L(kept_rows, kept_rows), Lkm = L(kept_rows, marg_idx),
                 Lmm = L(marg_idx, marg_idx);
  const VectorXd ek = eta(kept_rows), em = eta(marg_idx);
  const Eigen::LLT<MatrixXd> mm(Lmm);
  const MatrixXd L_ref = Lkk - Lkm * mm.solve(Lkm.transpose());
  const VectorXd eta_ref = ek - Lkm * mm.solve(em);
  ASSERT_EQ(L_ref.rows(), nk);

  const MatrixXd L_esdf = esdf.information().to_dense();
  const double dl = (L_esdf - L_ref).cwiseAbs().maxCoeff() / L_ref.cwiseAbs().maxCoeff();
  const double de =
      (esdf.information_vector() - eta_ref).cwiseAbs().maxCoeff() / eta_ref.cwiseAbs().maxCoeff();
  EXPECT_LT(dl, 1e-9);
  EXPECT_LT(de, 1e-9);
  // Same solution (one Gauss-Newton step from the linearisation point).
  ASSERT_TRUE(esdf.recover_mean_direct().ok());
  const VectorXd mu_ref = L_ref.ldlt().solve(eta_ref);
  EXPECT_LT((esdf.mean() - mu_ref).cwiseAbs().maxCoeff(), 1e-9 * mu_ref.cwiseAbs().maxCoeff());
  // Exact sparsity with 6-blocks: chain of kept poses + loop closures only.
  EXPECT_EQ(esdf.information().num_off_diagonal_pairs(), (block_of.size() - 1) + closures.size());
}

}  // namespace
}  // namespace nav::core
