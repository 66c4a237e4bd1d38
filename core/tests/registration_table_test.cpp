// RegistrationTable and registration_problem(): answers cross a trust boundary (LCM, dive logs),
// so a measurement or covariance the gate could not judge (NaN, out of range, asymmetric,
// indefinite) is refused with its reason before the filter sees it; failures carry no
// measurement and are kept; the first answer per pair wins.
#include "nav/core/navigation/registration_table.h"

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

namespace nav::core {
namespace {

Registration valid() {
  Registration r;
  r.frame_id_i = 3;
  r.frame_id_j = 7;
  r.success = true;
  r.z << 0.4, -0.2, 0.01, -0.02, 0.3;
  r.covariance = Eigen::Matrix<double, 5, 5>::Identity() * 1e-4;
  r.covariance(0, 1) = r.covariance(1, 0) = 2e-5;
  return r;
}

TEST(RegistrationProblem, AcceptsAValidAnswerAndAFailureWithoutMeasurement) {
  EXPECT_FALSE(registration_problem(valid()).has_value());
  Registration failed = valid();
  failed.success = false;
  failed.covariance.setConstant(std::numeric_limits<double>::quiet_NaN());
  EXPECT_FALSE(registration_problem(failed).has_value());
}

TEST(RegistrationProblem, RefusesWhatTheGateCouldNotJudgeWithTheReason) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Registration r = valid();
  r.frame_id_j = r.frame_id_i;
  EXPECT_NE(registration_problem(r).value_or("").find("must be smaller"), std::string::npos);

  r = valid();
  r.z(2) = nan;
  EXPECT_NE(registration_problem(r).value_or("").find("measurement is not finite"),
            std::string::npos);
  r = valid();
  r.z(1) = 2.0;  // elevation beyond pi/2
  EXPECT_NE(registration_problem(r).value_or("").find("component 1"), std::string::npos);

  r = valid();
  r.covariance(4, 4) = nan;
  EXPECT_NE(registration_problem(r).value_or("").find("covariance is not finite"),
            std::string::npos);
  r = valid();
  r.covariance(0, 3) = 5e-5;  // (3, 0) stays 0
  EXPECT_NE(registration_problem(r).value_or("").find("not symmetric"), std::string::npos);
  r = valid();
  r.covariance(2, 2) = -1e-6;  // symmetric, one negative eigenvalue
  EXPECT_NE(registration_problem(r).value_or("").find("not positive definite"), std::string::npos);
  r = valid();
  r.covariance.setZero();  // semi-definite: no information bound, refused too
  EXPECT_NE(registration_problem(r).value_or("").find("not positive definite"), std::string::npos);
}

// Found by daemon/fuzz/registration_fuzz.cpp: finite entries so large that the Frobenius norm
// overflows (the symmetry test compared inf with inf) and Cholesky pivots that overflow to NaN
// (which Eigen's LLT does not refuse) let an asymmetric covariance with zero variances through.
TEST(RegistrationProblem, RefusesHugeFiniteEntriesWhoseNormOverflows) {
  Registration r = valid();
  r.covariance(3, 3) = 0.0;
  r.covariance(4, 4) = 0.0;
  r.covariance(3, 0) = 7.29e251;  // lower triangle only: asymmetric
  r.covariance(2, 3) = 2.63e185;
  ASSERT_TRUE(r.covariance.allFinite());
  EXPECT_NE(registration_problem(r).value_or("").find("not symmetric"), std::string::npos);
  r.covariance(0, 3) = r.covariance(3, 0);  // symmetric now, still zero variances
  r.covariance(3, 2) = r.covariance(2, 3);
  EXPECT_NE(registration_problem(r).value_or("").find("not positive definite"), std::string::npos);
  // A valid covariance scaled to the largest finite doubles is still judged, not overflowed.
  r = valid();
  r.covariance *= 1e300 / r.covariance.maxCoeff();
  EXPECT_FALSE(registration_problem(r).has_value()) << registration_problem(r).value_or("");
}

TEST(RegistrationTable, InsertKeepsTheFirstAnswerAndThrowsTheReasonForAnInvalidOne) {
  RegistrationTable table;
  EXPECT_TRUE(table.insert(valid()));
  Registration second = valid();
  second.z(0) = -0.4;
  EXPECT_FALSE(table.insert(second));
  EXPECT_DOUBLE_EQ(table.find(7, 3)->z(0), 0.4);

  Registration indefinite = valid();
  indefinite.frame_id_j = 8;
  indefinite.covariance(2, 2) = -1e-6;
  try {
    table.insert(indefinite);
    FAIL() << "an indefinite covariance was inserted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("registration 3-8: covariance is not positive definite"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(table.size(), 1u);
  EXPECT_FALSE(table.find(3, 8).has_value());
}

}  // namespace
}  // namespace nav::core
