// ESDF acceptance tests: equality with a dense covariance-form EKF on a simulated survey,
// constant-time predict/update, bad-input rejection with bit-identical state, model overloads.
// (Eustice, Singh & Leonard, ICRA 2005; Eustice et al., RSS 2005.)
#include "nav/core/filter/esdf.h"

#include "nav/core/geometry/rotation.h"
#include "nav/core/models/binary_models.h"
#include "nav/core/models/unary_models.h"
#include "nav/core/sim/survey.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <numbers>

namespace nav::core {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

/// Covariance-form EKF on the full augmented state, block-ordered exactly like the ESDF
/// (robot block 0, delayed states at the indices the ESDF gives them). Every operation takes
/// the linearisation point from outside (the ESDF's mean), so both filters see the same
/// linearised system: prediction m' = f(μ) + F (m − μ), innovation ν − H (m − μ).
class DenseEkf {
 public:
  explicit DenseEkf(int d) : d_(d) {}
  void initialize(const VectorXd& x0, const MatrixXd& P0) {
    m_ = x0;
    P_ = P0;
  }
  void predict(const VectorXd& mu_t, const VectorXd& f, const MatrixXd& F, const MatrixXd& Q,
               bool keep) {
    const int n = static_cast<int>(m_.size());
    if (keep) {  // append a copy of the robot, then treat block 0 as the new robot
      m_.conservativeResize(n + d_);
      m_.tail(d_) = m_.head(d_);
      MatrixXd P(n + d_, n + d_);
      P.topLeftCorner(n, n) = P_;
      P.block(n, 0, d_, n) = P_.topRows(d_);
      P.block(0, n, n, d_) = P_.leftCols(d_);
      P.bottomRightCorner(d_, d_) = P_.topLeftCorner(d_, d_);
      P_ = P;
    }
    const int N = static_cast<int>(m_.size());
    const MatrixXd P_t_all = P_.topRows(d_);  // robot rows before predicting
    const MatrixXd Ptt = P_.topLeftCorner(d_, d_);
    m_.head(d_) = f + F * (m_.head(d_) - mu_t);
    P_.topRows(d_) = F * P_t_all;
    P_.leftCols(d_) = P_.topRows(d_).transpose().eval();  // overlaps at the corner
    P_.topLeftCorner(d_, d_) = F * Ptt * F.transpose() + Q;
    (void)N;
  }
  void update(const std::vector<std::pair<int, MatrixXd>>& H_blocks, const VectorXd& z,
              const VectorXd& h, const VectorXd& mu, const MatrixXd& R,
              const std::vector<bool>& angle) {
    const Eigen::Index m = z.size();
    MatrixXd H = MatrixXd::Zero(m, m_.size());
    for (const auto& [b, Hb] : H_blocks) H.middleCols(Eigen::Index{b} * d_, d_) = Hb;
    VectorXd nu = z - h;
    for (Eigen::Index r = 0; r < m; ++r) {
      if (angle[static_cast<size_t>(r)]) nu[r] = wrap_angle(nu[r]);
    }
    nu -= H * (m_ - mu);
    const MatrixXd PHt = P_ * H.transpose();
    const MatrixXd S = H * PHt + R;
    const MatrixXd K = S.llt().solve(PHt.transpose()).transpose();
    m_ += K * nu;
    P_ -= K * S * K.transpose();
    P_ = (0.5 * (P_ + P_.transpose())).eval();
  }
  const VectorXd& mean() const { return m_; }
  const MatrixXd& cov() const { return P_; }

 private:
  int d_;
  VectorXd m_;
  MatrixXd P_;
};

double rel_diff(const MatrixXd& a, const MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

template <class Model>
void update_both(Esdf& esdf, DenseEkf& ekf, const Model& model, int block, const MeasVec& z,
                 const MeasCov& R) {
  MeasJac H;
  const MeasVec h = model.predict(esdf.mean_block(block), &H);
  AngleMask mask;
  std::vector<bool> angle;
  for (int r = 0; r < model.dim(); ++r) {
    mask.is_angle[static_cast<size_t>(r)] = model.is_angle(r);
    angle.push_back(model.is_angle(r));
  }
  const VectorXd mu = esdf.mean();
  ASSERT_TRUE(esdf.update(block, z, h, H, R, mask).ok());
  ekf.update({{block, MatrixXd(H)}}, z, h, mu, R, angle);
}

void link_both(Esdf& esdf, DenseEkf& ekf, const CameraRelativePoseModel& model, int a, int b,
               const MeasVec& z, const MeasCov& R) {
  MeasJac Ha, Hb;
  const MeasVec h = model.predict(esdf.mean_block(a), esdf.mean_block(b), &Ha, &Hb);
  AngleMask mask;
  std::vector<bool> angle(5, true);
  for (int r = 0; r < 5; ++r) mask.is_angle[static_cast<size_t>(r)] = true;
  const VectorXd mu = esdf.mean();
  ASSERT_TRUE(esdf.update(a, b, z, h, Ha, Hb, R, mask).ok());
  ekf.update({{a, MatrixXd(Ha)}, {b, MatrixXd(Hb)}}, z, h, mu, R, angle);
}

// Acceptance test 1: 50 images with DVL, heading, attitude, depth, temporal and cross-track
// camera links. The mean is recovered only every third step, so the linearisation point is
// often a stale prediction: both filters must still agree to 1e-9 (relative, max-norm).
TEST(Esdf, EqualsDenseEkfOnSimulatedSurvey) {
  sim::SurveyOptions opt;
  opt.num_images = 50;
  opt.seed = 11;
  const sim::Survey sv = sim::simulate_survey(opt);
  ASSERT_GT(sv.num_cross_track_links, 0u) << "survey must contain loop closures";

  Esdf esdf(12);
  DenseEkf ekf(12);
  ASSERT_TRUE(esdf.initialize(sv.x0_mean, sv.P0).ok());
  ekf.initialize(sv.x0_mean, sv.P0);
  std::vector<int> image_blocks;
  double worst_mean = 0, worst_cov = 0;
  for (size_t s = 0; s < sv.steps.size(); ++s) {
    const sim::SurveyStep& st = sv.steps[s];
    Mat12 F, Q;
    const Vec12 mu_t = esdf.mean_block(0);
    const Vec12 f = sim::predicted_mean(sv, st, mu_t, &F, &Q);
    int kept = -1;
    ASSERT_TRUE(esdf.predict(f, F, Q, st.image >= 0, &kept).ok());
    ekf.predict(mu_t, f, F, Q, st.image >= 0);
    if (st.image >= 0) image_blocks.push_back(kept);
    update_both(esdf, ekf, sv.dvl, 0, st.dvl, sv.R_dvl);
    update_both(esdf, ekf, sv.heading, 0, st.heading, sv.R_heading);
    update_both(esdf, ekf, sv.attitude, 0, st.attitude, sv.R_attitude);
    update_both(esdf, ekf, sv.depth, 0, st.depth, sv.R_depth);
    for (const sim::CameraLink& l : st.links) {
      link_both(esdf, ekf, sv.camera, image_blocks[static_cast<size_t>(l.image_a)],
                image_blocks[static_cast<size_t>(l.image_b)], l.z, sv.R_camera);
    }
    if (s % 3 == 2 || s + 1 == sv.steps.size()) {
      ASSERT_TRUE(esdf.recover_mean_direct().ok());
      worst_mean = std::max(worst_mean, rel_diff(esdf.mean(), ekf.mean()));
    }
    if (s % 40 == 39 || s + 1 == sv.steps.size()) {
      const MatrixXd Lambda = esdf.information().to_dense();
      const MatrixXd Sigma = Lambda.ldlt().solve(MatrixXd::Identity(Lambda.rows(), Lambda.cols()));
      worst_cov = std::max(worst_cov, rel_diff(Sigma, ekf.cov()));
    }
  }
  EXPECT_EQ(esdf.num_blocks(), 51);
  EXPECT_EQ(ekf.mean().size(), 51 * 12);
  EXPECT_LT(worst_mean, 1e-9);
  EXPECT_LT(worst_cov, 1e-9);
  std::printf("ESDF vs dense EKF: max relative mean difference %.3g, covariance %.3g\n",
              worst_mean, worst_cov);
}

// Builds a filter with n delayed states in a chain plus a few camera-like links.
Esdf chain_filter(int n) {
  Esdf f(12);
  EXPECT_TRUE(f.initialize(Vec12::Zero(), Mat12::Identity()).ok());
  const Mat12 F = Mat12::Identity();
  const Mat12 Q = 0.01 * Mat12::Identity();
  for (int k = 0; k < n; ++k) {
    const Vec12 x = f.mean_block(0);
    EXPECT_TRUE(f.predict(x, F, Q, true).ok());
  }
  return f;
}

struct OpStats {
  UpdateStats predict, predict_keep, unary, binary;
};

OpStats measure_ops(int n) {
  Esdf f = chain_filter(n);
  OpStats s;
  Mat12 F = Mat12::Identity();
  F.topRightCorner<6, 6>() = 0.5 * Mat6::Identity();
  const Mat12 Q = 0.01 * Mat12::Identity();
  EXPECT_TRUE(f.predict(Vec12(f.mean_block(0)), F, Q, false).ok());
  s.predict = f.last_stats();
  EXPECT_TRUE(f.predict(Vec12(f.mean_block(0)), F, Q, true).ok());
  s.predict_keep = f.last_stats();
  const MeasVec z = MeasVec::Zero(1);
  const MeasCov R = MeasCov::Identity(1, 1);
  EXPECT_TRUE(f.update(HeadingModel{}, 0, z, R).ok());
  s.unary = f.last_stats();
  RelativePose6Model rel;
  const MeasVec z6 = MeasVec::Zero(6);
  const MeasCov R6 = MeasCov::Identity(6, 6);
  // A loop closure between the newest delayed state and one from the start of the map.
  EXPECT_TRUE(f.update(rel, 2, f.num_blocks() - 1, z6, R6).ok());
  s.binary = f.last_stats();
  return s;
}

void expect_same(const UpdateStats& a, const UpdateStats& b, const char* what) {
  EXPECT_EQ(a.blocks_written, b.blocks_written) << what;
  EXPECT_EQ(a.segments_written, b.segments_written) << what;
  EXPECT_EQ(a.neighbours, b.neighbours) << what;
  EXPECT_GT(a.blocks_written, 0) << what;
}

// Acceptance test 3: work per operation does not depend on the map size.
TEST(Esdf, BlocksTouchedIndependentOfMapSize) {
  const OpStats small = measure_ops(10);
  const OpStats large = measure_ops(5000);
  expect_same(small.predict, large.predict, "predict");
  expect_same(small.predict_keep, large.predict_keep, "predict keep");
  expect_same(small.unary, large.unary, "unary update");
  expect_same(small.binary, large.binary, "binary update");
  // Marginalising the robot with its single neighbour (newest delayed state): the robot row is
  // cleared (diagonal + 2 halves), then diagonal, robot-neighbour pair and neighbour diagonal.
  EXPECT_EQ(small.predict.neighbours, 1);
  EXPECT_EQ(small.predict.blocks_written, 3 + 1 + 2 + 1);
  EXPECT_EQ(small.unary.blocks_written, 1);
  EXPECT_EQ(small.binary.blocks_written, 4);
}

TEST(Esdf, ModelPredictEqualsGenericPredict) {
  ConstantVelocityModel model;
  Vec12 x0;
  x0 << 1, 2, 10, 0.05, -0.03, 0.7, 0.5, 0.02, -0.01, 0.01, 0.002, 0.05;
  const Mat12 P0 = 0.01 * Mat12::Identity();
  Esdf a(12), b(12);
  ASSERT_TRUE(a.initialize(x0, P0).ok());
  ASSERT_TRUE(b.initialize(x0, P0).ok());
  for (bool keep : {true, false, false, true, false}) {
    ASSERT_TRUE(a.predict(model, 0.5, keep).ok());
    Mat12 F;
    const Vec12 x = b.mean_block(0);
    const Vec12 f = model.predict(x, 0.5, &F);
    ASSERT_TRUE(b.predict(f, F, model.process_noise(x, 0.5), keep).ok());
  }
  EXPECT_EQ(a.information().to_dense(), b.information().to_dense());
  EXPECT_EQ(a.information_vector(), b.information_vector());
  EXPECT_EQ(a.mean(), b.mean());
  EXPECT_EQ(a.num_blocks(), 3);
}

// Filter state, compared bit for bit.
struct Snapshot {
  MatrixXd info;
  VectorXd eta, mean;
  size_t pairs;
  explicit Snapshot(const Esdf& f)
      : info(f.information().to_dense()),
        eta(f.information_vector()),
        mean(f.mean()),
        pairs(f.information().num_off_diagonal_pairs()) {}
  bool operator==(const Snapshot& o) const {
    return info.rows() == o.info.rows() && info == o.info && eta == o.eta && mean == o.mean &&
           pairs == o.pairs;
  }
};

void expect_error(const Status& s, StatusCode code, const std::string& needle) {
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.code(), code) << s.to_string();
  EXPECT_NE(s.message().find(needle), std::string::npos)
      << "message '" << s.message() << "' should mention '" << needle << "'";
}

// Acceptance test 5: bad input is rejected with a Status naming the problem, and the filter
// is bit-identical afterwards.
TEST(Esdf, BadInputLeavesFilterUnchanged) {
  Esdf f = chain_filter(3);
  ASSERT_TRUE(f.update(RelativePose6Model{}, 1, 3, MeasVec::Zero(6), MeasCov::Identity(6, 6)).ok());
  ASSERT_TRUE(f.recover_mean_direct().ok());
  const Snapshot before(f);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const HeadingModel heading;
  const MeasCov R1 = MeasCov::Identity(1, 1);
  MeasVec z1 = MeasVec::Zero(1);

  z1[0] = nan;
  expect_error(f.update(heading, 0, z1, R1), StatusCode::kInvalidArgument, "z");
  z1[0] = inf;
  expect_error(f.update(heading, 0, z1, R1), StatusCode::kInvalidArgument, "non-finite");
  z1[0] = 0.1;
  expect_error(f.update(heading, 0, z1, -R1), StatusCode::kNotPositiveDefinite, "R");
  MeasCov Rasym(2, 2);
  Rasym << 1, 0.5, 0, 1;
  expect_error(f.update(AttitudeModel{}, 0, MeasVec::Zero(2), Rasym),
               StatusCode::kNotPositiveDefinite, "symmetric");
  MeasCov Rnan = R1;
  Rnan(0, 0) = nan;
  expect_error(f.update(heading, 0, z1, Rnan), StatusCode::kInvalidArgument, "R");
  expect_error(f.update(heading, 7, z1, R1), StatusCode::kUnknownState, "block 7");
  expect_error(f.update(heading, -1, z1, R1), StatusCode::kUnknownState, "block -1");
  expect_error(f.update(heading, 0, MeasVec::Zero(3), R1), StatusCode::kInvalidArgument,
               "h(mean) is 1x1, expected 3x1");
  MeasJac Hbad = MeasJac::Zero(1, 6);
  AngleMask mask;
  expect_error(f.update(0, z1, MeasVec::Zero(1), Hbad, R1, mask), StatusCode::kInvalidArgument,
               "H is 1x6");
  MeasJac Hnan = MeasJac::Zero(1, 12);
  Hnan(0, 5) = nan;
  expect_error(f.update(0, z1, MeasVec::Zero(1), Hnan, R1, mask), StatusCode::kInvalidArgument,
               "H");
  expect_error(f.update(RelativePose6Model{}, 2, 2, MeasVec::Zero(6), MeasCov::Identity(6, 6)),
               StatusCode::kInvalidArgument, "two different blocks");
  expect_error(f.update(RelativePose6Model{}, 2, 9, MeasVec::Zero(6), MeasCov::Identity(6, 6)),
               StatusCode::kUnknownState, "block 9");

  const Mat12 I = Mat12::Identity();
  Mat12 Fnan = I;
  Fnan(3, 4) = nan;
  expect_error(f.predict(Vec12::Zero(), Fnan, I, false), StatusCode::kInvalidArgument, "F");
  expect_error(f.predict(Vec12::Zero(), I, -I, true), StatusCode::kNotPositiveDefinite, "Q");
  expect_error(f.predict(VectorXd::Zero(6), I, I, true), StatusCode::kInvalidArgument,
               "f(mean) is 6x1");
  expect_error(f.predict(Vec12::Zero(), MatrixXd::Identity(6, 6), I, false),
               StatusCode::kInvalidArgument, "F is 6x6");
  ConstantVelocityModel cv;
  expect_error(f.predict(cv, -1.0, false), StatusCode::kInvalidArgument, "model");
  expect_error(f.predict(cv, nan, true), StatusCode::kInvalidArgument, "model");
  expect_error(f.set_mean(VectorXd::Zero(5)), StatusCode::kInvalidArgument, "5 elements");
  VectorXd mean_nan = f.mean();
  mean_nan[17] = nan;
  expect_error(f.set_mean(mean_nan), StatusCode::kInvalidArgument, "mean");
  expect_error(f.initialize(Vec12::Zero(), -Mat12::Identity()), StatusCode::kNotPositiveDefinite,
               "P0");
  EXPECT_TRUE(Snapshot(f) == before) << "filter changed by rejected input";

  // Pitch at the Euler singularity: the model refuses, the filter reports out-of-range.
  Esdf g(12);
  Vec12 x0 = Vec12::Zero();
  x0[kPitch] = 89.9 * std::numbers::pi / 180.0;
  x0[kQ] = 0.1;
  ASSERT_TRUE(g.initialize(x0, Mat12::Identity()).ok());
  const Snapshot g_before(g);
  expect_error(g.predict(cv, 0.5, false), StatusCode::kOutOfRange, "pitch");
  EXPECT_TRUE(Snapshot(g) == g_before);

  // Uninitialised filter.
  Esdf h(12);
  expect_error(h.predict(cv, 0.5, false), StatusCode::kUnknownState, "not initialised");
  expect_error(h.update(heading, 0, z1, R1), StatusCode::kUnknownState, "block 0");
}

}  // namespace
}  // namespace nav::core
