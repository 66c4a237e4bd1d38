// Chi-square CDF and quantile (navigation/chi_square.h) against table values (Abramowitz &
// Stegun table 26.8), the closed form for 2 dof, and the 6-dof -> 5-dof gate conversion.
#include "nav/core/navigation/chi_square.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace nav::core {
namespace {

TEST(ChiSquare, MatchesTablesAndConvertsTheSixDofGate) {
  EXPECT_NEAR(chi_square_quantile(0.99, 6), 16.812, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.99, 5), 15.086, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.95, 1), 3.841, 1e-3);
  EXPECT_NEAR(chi_square_quantile(0.99, 2), 9.210, 1e-3);
  EXPECT_NEAR(chi_square_cdf(2.0, 2), 1.0 - std::exp(-1.0), 1e-14);
  EXPECT_NEAR(equivalent_chi_square_gate(16.81, 6, 5), 15.08, 0.01);
  EXPECT_THROW(chi_square_cdf(1.0, 0), std::invalid_argument);
}

TEST(ChiSquare, QuantileInvertsTheCdf) {
  for (int dof : {1, 2, 5, 6, 12, 100}) {
    for (double p : {0.01, 0.5, 0.95, 0.999}) {
      EXPECT_NEAR(chi_square_cdf(chi_square_quantile(p, dof), dof), p, 1e-10)
          << dof << " dof, p " << p;
    }
  }
}

}  // namespace
}  // namespace nav::core
