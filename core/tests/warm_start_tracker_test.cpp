// WarmStartTracker (navigation/warm_start_tracker.h): the composed map A and the tracked robot
// covariance P after predictions and Kalman updates, and replay_from, which recomputes both
// from another starting Σ_tt (the recovery thread's hand-off). Reference: a second tracker
// restarted from that Σ_tt and fed the same steps, and a dense Kalman filter by hand.
#include "nav/core/navigation/warm_start_tracker.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace nav::core {
namespace {

Mat12 random_spd(std::mt19937& rng, double scale) {
  std::normal_distribution<double> normal;
  Mat12 A;
  for (int i = 0; i < A.size(); ++i) A(i) = normal(rng);
  return scale * (A * A.transpose() / 12.0 + 0.1 * Mat12::Identity());
}

struct Steps {
  std::vector<Mat12> F, Q;
  std::vector<MeasJac> H;
  std::vector<MeasCov> R;
};

Steps random_steps(unsigned seed, int count) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Steps s;
  for (int k = 0; k < count; ++k) {
    Mat12 F = Mat12::Identity();
    for (int i = 0; i < 12; ++i) F(i, (i + 6) % 12) = 0.05 * normal(rng);
    s.F.push_back(F);
    s.Q.push_back(random_spd(rng, 1e-4));
    const int m = 1 + k % 6;
    MeasJac H(m, 12);
    for (int i = 0; i < H.size(); ++i) H(i) = normal(rng);
    s.H.push_back(H);
    s.R.push_back(random_spd(rng, 1e-2).topLeftCorner(m, m));
  }
  return s;
}

void feed(WarmStartTracker& t, const Steps& s) {
  for (std::size_t k = 0; k < s.F.size(); ++k) {
    t.predicted_with(s.F[k], s.Q[k], -1);
    t.updated_with(s.H[k], s.R[k]);
  }
}

TEST(WarmStartTracker, TracksTheKalmanFilterOfTheRobot) {
  std::mt19937 rng(1);
  const Steps s = random_steps(2, 20);
  WarmStartTracker t;
  const Mat12 sigma = random_spd(rng, 1.0);
  t.restart(sigma);
  feed(t, s);
  // By hand: P⁺ = (P⁻¹ + Hᵀ R⁻¹ H)⁻¹ and I − K H = P⁺ P⁻¹ (information form).
  Eigen::MatrixXd P = sigma, A = Mat12::Identity();
  for (std::size_t k = 0; k < s.F.size(); ++k) {
    P = s.F[k] * P * s.F[k].transpose() + s.Q[k];
    A = s.F[k] * A;
    const Eigen::MatrixXd H = s.H[k], R = s.R[k];
    const Eigen::MatrixXd post = (P.inverse() + H.transpose() * R.inverse() * H).inverse();
    A = post * P.inverse() * A;
    P = post;
  }
  EXPECT_LT((t.P - P).norm(), 1e-9 * P.norm());
  EXPECT_LT((t.A - A).norm(), 1e-9 * A.norm());
}

TEST(WarmStartTracker, ReplayFromAnotherStartEqualsATrackerStartedThere) {
  std::mt19937 rng(3);
  const Steps s = random_steps(4, 30);
  const Mat12 stale = random_spd(rng, 1.0), exact = random_spd(rng, 0.3);
  WarmStartTracker t;
  t.record_steps = true;
  t.restart(stale);
  feed(t, s);
  ASSERT_EQ(t.steps.size(), 60u);
  WarmStartTracker reference;
  reference.restart(exact);
  feed(reference, s);
  t.replay_from(exact);
  EXPECT_EQ(t.sigma_tt, exact);
  EXPECT_LT((t.P - reference.P).norm(), 1e-12 * reference.P.norm());
  EXPECT_LT((t.A - reference.A).norm(), 1e-12 * reference.A.norm());
  // Further steps append; a restart forgets them.
  t.predicted_with(s.F[0], s.Q[0], 3);
  EXPECT_EQ(t.steps.size(), 61u);
  EXPECT_EQ(t.kept, 3);
  t.restart(exact);
  EXPECT_TRUE(t.steps.empty());
}

TEST(WarmStartTracker, ReplayFromAnIndefiniteStartKeepsTheTrackedCovariance) {
  std::mt19937 rng(5);
  const Steps s = random_steps(6, 5);
  WarmStartTracker t;
  t.record_steps = true;
  t.restart(random_spd(rng, 1.0));
  feed(t, s);
  const Mat12 P = t.P, A = t.A;
  Mat12 indefinite = random_spd(rng, 1.0);
  indefinite(0, 0) = -1e3;
  t.replay_from(indefinite);
  EXPECT_EQ(t.P, P);
  EXPECT_EQ(t.A, A);
  EXPECT_EQ(t.sigma_tt, indefinite);
}

}  // namespace
}  // namespace nav::core
