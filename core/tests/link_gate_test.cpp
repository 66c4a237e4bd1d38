// The camera link gate's Mahalanobis distance (navigation/link_gate.h): LLT of S, so that an
// indefinite innovation covariance (a joint that is not PSD) can never pass the gate with a
// negative d², which an LDLT without a sign check of D would return.
#include "nav/core/navigation/link_gate.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <limits>

namespace nav::core {
namespace {

TEST(LinkGate, MahalanobisDistanceOfAPositiveDefiniteS) {
  Eigen::Matrix<double, 5, 5> S = Eigen::Matrix<double, 5, 5>::Identity();
  S(0, 0) = 4.0;
  S(0, 1) = S(1, 0) = 0.5;
  MeasVec nu(5);
  nu << 1.0, -2.0, 0.5, 0.0, 3.0;
  double d2 = -1.0;
  ASSERT_TRUE(LinkGate::mahalanobis_sq(S, nu, &d2));
  EXPECT_NEAR(d2, nu.dot(S.inverse() * nu), 1e-12);
}

TEST(LinkGate, IndefiniteInnovationCovarianceNeverPasses) {
  // One negative eigenvalue along the innovation: νᵀ S⁻¹ ν = -9 would pass any gate.
  Eigen::Matrix<double, 5, 5> S = Eigen::Matrix<double, 5, 5>::Identity();
  S(4, 4) = -1.0;
  MeasVec nu = MeasVec::Zero(5);
  nu[4] = 3.0;
  EXPECT_LT(nu.dot(S.ldlt().solve(nu)), 0.0);  // what an unchecked LDLT gives
  double d2 = 0.0;
  EXPECT_FALSE(LinkGate::mahalanobis_sq(S, nu, &d2));
  // Singular (PSD but not PD) and non-finite S are refused too.
  S(4, 4) = 0.0;
  EXPECT_FALSE(LinkGate::mahalanobis_sq(S, nu, &d2));
  S(4, 4) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(LinkGate::mahalanobis_sq(S, nu, &d2));
}

}  // namespace
}  // namespace nav::core
