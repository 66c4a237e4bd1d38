// Acceptance test 4: Monte Carlo consistency of the ESDF on the simulated survey (truth is
// drawn from the filter's own process and sensor models). The average normalised estimation
// error squared (NEES) of the final robot pose over N runs must lie in the two-sided 95 %
// interval of chi2(N d) / N (Bar-Shalom, Li & Kirubarajan 2001, section 5.4).
#include "nav/core/filter/esdf.h"
#include "nav/core/geometry/rotation.h"
#include "nav/core/sim/survey.h"

#include <gtest/gtest.h>

#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <cmath>

namespace nav::core {
namespace {

/// Wilson-Hilferty approximation of the chi-square quantile with k degrees of freedom at the
/// standard-normal quantile z (relative error < 1e-3 for k > 100).
double chi2_quantile(double k, double z) {
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z * std::sqrt(a), 3);
}

/// Robot pose covariance: first 6 columns of Λ⁻¹ E_r by sparse Cholesky.
Mat6 robot_pose_covariance(const Esdf& f) {
  const Eigen::SparseMatrix<double> L = f.information().to_sparse();
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>> chol(L);
  EXPECT_EQ(chol.info(), Eigen::Success);
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(L.rows(), 6);
  E.topRows<6>().setIdentity();
  const Eigen::MatrixXd X = chol.solve(E);
  return X.topRows<6>();
}

TEST(EsdfConsistency, FinalRobotPoseNeesWithinChiSquareBounds) {
  constexpr int kRuns = 50;
  constexpr int kDim = 6;
  double nees_sum = 0.0;
  for (int run = 0; run < kRuns; ++run) {
    sim::SurveyOptions opt;
    opt.num_images = 50;  // 2.5 track lines: temporal links and cross-track loop closures
    opt.seed = 1000 + static_cast<std::uint64_t>(run);
    const sim::Survey sv = sim::simulate_survey(opt);
    Esdf esdf(12);
    ASSERT_TRUE(esdf.initialize(sv.x0_mean, sv.P0).ok());
    std::vector<int> image_blocks;
    for (size_t k = 0; k < sv.steps.size(); ++k) {
      const Status s = sim::apply_step(sv, sv.steps[k], esdf, image_blocks);
      ASSERT_TRUE(s.ok()) << s.to_string();
      // Relinearise every other step (as a recovery thread would) and at the end.
      if (k % 2 == 1 || k + 1 == sv.steps.size()) {
        ASSERT_TRUE(esdf.recover_mean_direct().ok());
      }
    }
    const Vec6 x_true = sv.steps.back().x_true.head<6>();
    Vec6 e = x_true - Vec6(esdf.mean_block(Esdf::kRobotBlock).head<6>());
    for (int k = 3; k < 6; ++k) e[k] = wrap_angle(e[k]);
    const Mat6 P = robot_pose_covariance(esdf);
    nees_sum += e.dot(P.ldlt().solve(e));
  }
  const double nees = nees_sum / kRuns;
  const double lo = chi2_quantile(kRuns * kDim, -1.959964) / kRuns;
  const double hi = chi2_quantile(kRuns * kDim, 1.959964) / kRuns;
  std::printf("average NEES of the final robot pose over %d runs: %.3f (95%% bounds %.3f..%.3f)\n",
              kRuns, nees, lo, hi);
  EXPECT_GT(nees, lo);
  EXPECT_LT(nees, hi);
}

}  // namespace
}  // namespace nav::core
