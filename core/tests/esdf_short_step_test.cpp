// Esdf::predict over steps of a few milliseconds (esdf.cpp, Prediction): Q's pose block is then
// ~dt³, and forming the robot's information as Q⁻¹ − A Ω⁻¹ Aᵀ lost about six digits per step.
// A robot 3.8 km deep with one delayed state, predicted by the constant-velocity model in steps
// of 5 and 95 ms for 200 s without a measurement (the robot's uncertainty grows while Q⁻¹ of
// the short steps does not: the hardest case for that difference), must keep its marginal
// covariance and mean as the covariance-form recursion P ← F P Fᵀ + Q, x ← f(x) gives them in
// long double, with the same F, Q and f. The difference form fails this by orders of magnitude
// (docs/consistency.md "The dead-reckoning baseline").
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "nav/core/filter/esdf.h"
#include "nav/core/models/constant_velocity.h"

namespace nav::core {
namespace {

using LongMat = Eigen::Matrix<long double, 12, 12>;
using LongVec = Eigen::Matrix<long double, 12, 1>;

TEST(EsdfShortSteps, RobotMarginalStaysTheCovarianceRecursion) {
  ConstantVelocityOptions noise;
  noise.accel_psd = Vec3::Constant(1e-3);
  noise.angular_accel_psd = Vec3::Constant(7e-5);
  const ConstantVelocityModel model(noise);
  Vec12 x0;
  x0 << 120.0, -45.0, 3785.0, 0.01, -0.02, 1.2, 0.5, 0.01, 0.02, 0.001, -0.002, 0.01;
  Vec12 sigma;
  sigma << 0.01, 0.01, 0.05, 0.002, 0.002, 0.002, 0.5, 0.5, 0.5, 0.05, 0.05, 0.05;
  const Mat12 P0 = sigma.array().square().matrix().asDiagonal();

  Esdf esdf(12);
  ASSERT_TRUE(esdf.initialize(x0, P0).ok());
  LongMat P = P0.cast<long double>();
  LongVec x = x0.cast<long double>();
  for (int k = 0; k < 4000; ++k) {
    const double dt_s = k % 2 == 0 ? 0.005 : 0.095;
    const Vec12 mean = esdf.mean_block(Esdf::kRobotBlock);
    Mat12 F;
    const Vec12 f = model.predict(mean, dt_s, &F);
    const Mat12 Q = model.process_noise(mean, dt_s);
    ASSERT_TRUE(esdf.predict(f, F, Q, /*keep_current=*/k == 0).ok()) << "step " << k;
    // The recursion, linearised at the same mean: x' = f + F (x − mean).
    x = f.cast<long double>() + F.cast<long double>() * (x - mean.cast<long double>());
    P = F.cast<long double>() * P * F.cast<long double>().transpose() + Q.cast<long double>();
  }
  ASSERT_EQ(esdf.num_blocks(), 2) << "the robot and the state kept at the first step";

  const Eigen::Matrix<long double, 24, 24> lambda =
      esdf.information().to_dense().cast<long double>();
  const Eigen::Matrix<long double, 24, 1> eta = esdf.information_vector().cast<long double>();
  const Eigen::LDLT<Eigen::Matrix<long double, 24, 24>> ldlt(lambda);
  const Eigen::Matrix<long double, 24, 24> sigma_all =
      ldlt.solve(Eigen::Matrix<long double, 24, 24>::Identity());
  const LongMat sigma_rr = sigma_all.topLeftCorner<12, 12>();
  const LongVec mu_r = ldlt.solve(eta).head<12>();

  // Relative error of the marginal in its own metric: λmax(P^-½ (Σ_rr − P) P^-½).
  const Eigen::LLT<LongMat> p_llt(P);
  const LongMat L_inv = p_llt.matrixL().solve(LongMat::Identity());
  const LongMat scaled = L_inv * (sigma_rr - P) * L_inv.transpose();
  const double covariance_error = static_cast<double>(
      Eigen::SelfAdjointEigenSolver<LongMat>(scaled).eigenvalues().cwiseAbs().maxCoeff());
  // The mean's error in standard deviations of the marginal.
  const double mean_error_sigmas =
      static_cast<double>((mu_r - x).cwiseQuotient(P.diagonal().cwiseSqrt()).cwiseAbs().maxCoeff());
  std::printf(
      "robot marginal after 4000 short and long steps: covariance %.3g (relative), mean "
      "%.3g sigma\n",
      covariance_error, mean_error_sigmas);
  EXPECT_LT(covariance_error, 1e-8);
  EXPECT_LT(mean_error_sigmas, 1e-3);
}

}  // namespace
}  // namespace nav::core
