// Tests of the report library's readers and metrics (daemon/src/report/): CSV errors naming
// file:line and column, truth interpolation, XY RMS, NEES, conservative fraction, link counts,
// on hand-checkable inputs and on the fixture of support/report_fixture.h.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "nav/report/csv_table.h"
#include "nav/report/metrics.h"
#include "nav/report/replay_data.h"
#include "support/report_fixture.h"

namespace nav::report {
namespace {

namespace fs = std::filesystem;

/// Removes this process's temporary directories after the last test.
class RemoveTempDirs : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(
        fs::temp_directory_path() / ("report_metrics_test_" + std::to_string(::getpid())), ignored);
  }
};
[[maybe_unused]] ::testing::Environment* const kRemoveTempDirs =
    ::testing::AddGlobalTestEnvironment(new RemoveTempDirs);

fs::path fixture_root(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("report_metrics_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ReportError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(CsvTable, NonNumericCellNamesFileLineAndColumn) {
  const CsvTable t = CsvTable::parse("# c\nt_us,x_m\n1,2\n\n2,abc\n", "traj.csv");
  EXPECT_EQ(t.rows(), 2u);
  EXPECT_DOUBLE_EQ(t.number(0, 1), 2.0);
  EXPECT_EQ(error_of([&] { t.number(1, 1); }),
            "traj.csv:5: column 'x_m': 'abc' is not a finite number");
  EXPECT_EQ(error_of([&] {
              t.integer(0, t.column("x_m"));
              t.integer(1, 0);
              t.number(1, 1);
            }),
            "traj.csv:5: column 'x_m': 'abc' is not a finite number");
}

TEST(CsvTable, MissingColumnAndWrongFieldCountAreErrors) {
  const CsvTable t = CsvTable::parse("t_us,x_m\n1,2\n", "a.csv");
  EXPECT_EQ(error_of([&] { t.column("y_m"); }), "a.csv: missing column 'y_m' (header: t_us,x_m)");
  EXPECT_EQ(error_of([] { CsvTable::parse("t_us,x_m\n1,2\n3\n", "b.csv"); }),
            "b.csv:3: 1 fields, header has 2");
  EXPECT_EQ(error_of([] { CsvTable::parse("# only a comment\n", "c.csv"); }),
            "c.csv: empty file (no header line)");
  EXPECT_EQ(error_of([&] { CsvTable::parse("t_us\n1.5\n", "d.csv").integer(0, 0); }),
            "d.csv:2: column 't_us': '1.5' is not an integer");
}

TEST(Readers, StatesWithoutExactMarginalColumnsIsAnError) {
  const fs::path dir = fixture_root("states");
  test::write_file(dir / "states.csv",
                   "state_id,frame_id,t_us,x_m,y_m,z_m,roll_rad,pitch_rad,"
                   "heading_rad" +
                       test::matrix_header('b') + "\n");
  const std::string e = error_of([&] { read_states(dir / "states.csv"); });
  EXPECT_NE(e.find("states.csv: missing column 'e00'"), std::string::npos) << e;
}

TEST(Readers, LinkOutcomeMustBeOneOfTheFour) {
  const fs::path dir = fixture_root("links");
  test::write_file(dir / "links.csv",
                   "t_us,frame_i,frame_j,state_i,state_j,outcome,mahalanobis_sq,is_outlier\n"
                   "1,0,1,0,1,accepted,2,0\n1,0,2,0,2,maybe,2,0\n");
  const std::string e = error_of([&] { read_links(dir / "links.csv"); });
  EXPECT_NE(e.find("links.csv:3: column 'outcome': 'maybe'"), std::string::npos) << e;
}

TEST(Readers, BlockPatternNeedsTheDimensionLineAndIntegerPairs) {
  const fs::path dir = fixture_root("blocks");
  test::write_file(dir / "ok.csv", "# block_dim 12 num_blocks 3\n0,0\n0,1\n2,2\n");
  const BlockPattern p = read_block_pattern(dir / "ok.csv");
  EXPECT_EQ(p.block_dim, 12);
  EXPECT_EQ(p.num_blocks, 3);
  EXPECT_EQ(p.blocks.size(), 3u);
  test::write_file(dir / "bad.csv", "# block_dim 12 num_blocks 3\ni,j\n0,0\n1,x\n");
  EXPECT_EQ(error_of([&] { read_block_pattern(dir / "bad.csv"); }),
            (dir / "bad.csv").string() + ":4: '1,x' is not 'i,j' (two integers)");
  test::write_file(dir / "nodim.csv", "i,j\n0,0\n");
  EXPECT_NE(error_of([&] { read_block_pattern(dir / "nodim.csv"); }).find("no '# block_dim"),
            std::string::npos);
}

TEST(Metrics, TruthIsInterpolatedLinearlyAndAnglesTakeTheShortArc) {
  std::vector<TimedPose> truth(2);
  truth[0].t_us = 0;
  truth[0].pose << 0, 0, 1, 0, 0, M_PI - 0.1;
  truth[1].t_us = 10;
  truth[1].pose << 10, -20, 3, 0, 0, -M_PI + 0.1;
  const auto mid = truth_pose_at(truth, 5);
  ASSERT_TRUE(mid);
  EXPECT_NEAR((*mid)[0], 5.0, 1e-12);
  EXPECT_NEAR((*mid)[1], -10.0, 1e-12);
  EXPECT_NEAR((*mid)[2], 2.0, 1e-12);
  EXPECT_NEAR(std::abs((*mid)[5]), M_PI, 1e-12);  // through pi, not through 0
  EXPECT_FALSE(truth_pose_at(truth, 11));
  EXPECT_FALSE(truth_pose_at(truth, -1));
}

TEST(Metrics, ConstantOffsetsGiveExactRms) {
  const fs::path dir = fixture_root("rms");
  test::write_dive(dir / "dive");
  test::write_replay(dir / "out");
  const auto truth = read_timed_poses(dir / "dive/truth.csv");
  const XyError slam = xy_error(read_timed_poses(dir / "out/trajectory.csv"), truth, "slam");
  const XyError dr = xy_error(read_timed_poses(dir / "out/dead_reckoning.csv"), truth, "dr");
  EXPECT_NEAR(slam.rms_m, 1.0, 1e-12);
  EXPECT_NEAR(slam.final_m, 1.0, 1e-12);
  EXPECT_NEAR(dr.rms_m, 2.0, 1e-12);
  EXPECT_EQ(slam.samples, static_cast<size_t>(test::kImages));
  EXPECT_EQ(slam.outside_truth, 0u);
}

TEST(Metrics, RowsOutsideTheTruthSpanAreCountedNotUsed) {
  std::vector<TimedPose> truth(2), est(3);
  truth[1].t_us = 10;
  truth[1].pose[0] = 10;
  est[0].t_us = 0;  // error 0
  est[1].t_us = 10;
  est[1].pose[0] = 13;  // error 3
  est[2].t_us = 20;     // outside
  const XyError e = xy_error(est, truth, "est");
  EXPECT_NEAR(e.rms_m, std::sqrt(9.0 / 2.0), 1e-12);
  EXPECT_NEAR(e.final_m, 3.0, 1e-12);
  EXPECT_EQ(e.outside_truth, 1u);
  std::vector<TimedPose> late(1);
  late[0].t_us = 99;
  EXPECT_NE(error_of([&] { xy_error(late, truth, "late.csv"); }).find("late.csv: none of its 1"),
            std::string::npos);
}

TEST(Metrics, ChiSquareQuantilesMatchTables) {
  // Exact quantiles (regularised incomplete gamma, mpmath): chi2(6) 2.5 % = 1.23734,
  // 97.5 % = 14.44938; chi2(600): 534.01855, 669.76915. Wilson-Hilferty: 2.5 % low at k = 6,
  // < 0.01 at k = 600.
  EXPECT_NEAR(chi2_quantile(6, -1.959964), 1.23734, 0.04);
  EXPECT_NEAR(chi2_quantile(6, 1.959964), 14.44938, 0.1);
  EXPECT_NEAR(chi2_quantile(600, -1.959964), 534.01855, 0.01);
  EXPECT_NEAR(chi2_quantile(600, 1.959964), 669.76915, 0.01);
}

TEST(Metrics, NeesOfOneStateByHand) {
  DelayedState s;
  s.frame_id = 3;
  s.exact = core::Mat6::Identity() * 4.0;
  s.pose << 2, 0, 0, 0, 0, M_PI - 0.05;
  TrueImage im;
  im.frame_id = 3;
  im.pose << 0, 0, 0, 0, 0, -M_PI + 0.05;  // heading error 0.1 rad across the wrap
  DelayedState singular = s;               // a broken exact marginal is counted and skipped
  singular.exact.setZero();
  const NeesResult r = delayed_state_nees({s, singular}, {im}, {});
  ASSERT_EQ(r.nees.size(), 1u);
  EXPECT_EQ(r.exact_not_positive_definite, 1u);
  EXPECT_NEAR(r.mean, (4.0 + 0.01) / 4.0, 1e-9);
  EXPECT_NEAR(r.xy_rms_m, 2.0, 1e-12);
  EXPECT_EQ(r.robot_frame_id, 3);
  EXPECT_NEAR(r.robot_nees, (4.0 + 0.01) / 4.0, 1e-9);
  EXPECT_NEAR(r.robot_component[0], 1.0, 1e-12);
  EXPECT_NEAR(r.robot_component[5], 0.01 / 4.0, 1e-9);
  EXPECT_NEAR(r.component_mean[5], 0.01 / 4.0, 1e-9);
}

// Two published poses against a straight truth: one off by 0.2 m in x with a correlated x-y
// covariance (the NEES uses the full 6x6, the components only its diagonal), one off by 0.1 rad
// in heading across the ±π wrap; one outside the truth span, one with a singular covariance.
TEST(Metrics, PublishedNeesByHandAndPerComponent) {
  std::vector<TimedPose> truth(2);
  truth[0].pose << 0, 0, 0, 0, 0, M_PI - 0.05;
  truth[1].t_us = 10;
  truth[1].pose << 10, 0, 0, 0, 0, M_PI - 0.05;
  daemon::PublishedSolution a, b;
  a.t_us = 5;
  a.pose << 5.2, 0, 0, 0, 0, M_PI - 0.05;
  a.covariance = core::Mat6::Identity() * 0.01;
  a.covariance(0, 1) = a.covariance(1, 0) = 0.005;
  b.t_us = 10;
  b.pose << 10, 0, 0, 0, 0, -M_PI + 0.05;  // heading error +0.1 rad
  b.covariance = core::Mat6::Identity() * 0.01;
  daemon::PublishedSolution outside = b, singular = b;
  outside.t_us = 11;
  singular.covariance.setZero();
  const PublishedNees r = published_nees({a, b, outside, singular}, truth);
  ASSERT_EQ(r.samples, 2u);
  EXPECT_EQ(r.outside_truth, 1u);
  EXPECT_EQ(r.not_positive_definite, 1u);
  // a: [0.2, 0] through [[0.01, 0.005], [0.005, 0.01]]⁻¹ = 0.04 * 0.01 / 0.000075 = 16/3.
  const double nees_a = 16.0 / 3.0, nees_b = 1.0;
  EXPECT_NEAR(r.mean, 0.5 * (nees_a + nees_b), 1e-9);
  EXPECT_NEAR(r.exceed_99_fraction, 0.0, 0.0);
  EXPECT_NEAR(r.component_mean[0], 0.5 * 4.0, 1e-9);  // 0.04 / 0.01 in a, 0 in b
  EXPECT_NEAR(r.component_mean[1], 0.0, 1e-12);
  EXPECT_NEAR(r.component_mean[5], 0.5 * 1.0, 1e-9);  // 0.01 / 0.01 in b
}

TEST(Metrics, RobotPoseNeesIsTheNewestStateWithATruthPose) {
  TrueImage a, b;
  a.frame_id = 5;
  b.frame_id = 9;
  DelayedState older, newest, no_truth;
  older.frame_id = 5;
  older.exact = core::Mat6::Identity();
  older.pose << 0, 0, 3, 0, 0, 0;  // NEES 9 (z)
  newest = older;
  newest.frame_id = 9;
  newest.pose << 0, 1, 0, 0, 0, 0;  // NEES 1 (y)
  no_truth = older;
  no_truth.frame_id = 12;  // newer, but without a true pose: skipped and counted
  const NeesResult r = delayed_state_nees({newest, no_truth, older}, {a, b}, {});
  EXPECT_EQ(r.without_truth, 1u);
  EXPECT_EQ(r.robot_frame_id, 9);
  EXPECT_NEAR(r.robot_nees, 1.0, 1e-12);
  EXPECT_NEAR(r.robot_component[1], 1.0, 1e-12);
  EXPECT_NEAR(r.robot_component[2], 0.0, 1e-12);
  EXPECT_NEAR(r.mean, 5.0, 1e-12);
  EXPECT_NEAR(r.component_mean[2], 4.5, 1e-12);
}

TEST(Metrics, NeesOfStatesDrawnFromTheirCovarianceIsNearTheDof) {
  const fs::path dir = fixture_root("nees");
  test::write_dive(dir / "dive");
  test::write_replay(dir / "out");
  const auto states = read_states(dir / "out/states.csv");
  const NeesResult r = delayed_state_nees(states, read_images(dir / "dive/images.csv"), {});
  EXPECT_EQ(r.nees.size(), static_cast<size_t>(test::kImages));
  // The fixture's errors are independent draws, so here (unlike a real dive's correlated
  // states) the mean of the 40 is chi2(240) / 40: 2.5 % 198.98385, 97.5 % 284.80248.
  EXPECT_GT(r.mean, 198.98385 / 40);
  EXPECT_LT(r.mean, 284.80248 / 40);
  EXPECT_GT(r.robot_nees, kChi2Dof6Interval95.first);
  EXPECT_LT(r.robot_nees, kChi2Dof6Interval95.second);
  // Same states against truth.csv interpolated at the state times: the same NEES.
  const NeesResult by_time =
      delayed_state_nees(states, {}, read_timed_poses(dir / "dive/truth.csv"));
  EXPECT_NEAR(by_time.mean, r.mean, 1e-9);
}

TEST(Metrics, ConservativeFractionAndLinkCountsOfTheFixture) {
  const fs::path dir = fixture_root("counts");
  test::write_replay(dir / "out");
  const auto states = read_states(dir / "out/states.csv");
  const ConservativeResult c = conservative_bounds(states, 1e-9);
  EXPECT_EQ(c.checked, 40u);
  EXPECT_EQ(c.conservative, 36u);  // every 10th bound is 0.5 E
  EXPECT_LT(c.worst_min_eigenvalue, 0.0);
  const LinkCounts l = count_links(read_links(dir / "out/links.csv"));
  EXPECT_EQ(l.proposed, 10u);
  EXPECT_EQ(l.accepted, 6u);
  EXPECT_EQ(l.camera_links, 5u);
  EXPECT_EQ(l.gated, 2u);
  EXPECT_EQ(l.registration_failed, 1u);
  EXPECT_EQ(l.not_registered, 1u);
  EXPECT_EQ(l.outliers_proposed, 3u);
  EXPECT_EQ(l.outliers_rejected, 2u);
  EXPECT_EQ(l.outliers_accepted, 1u);
}

TEST(Metrics, ComputeMetricsWithoutADiveHasNullTruthMetrics) {
  const fs::path dir = fixture_root("nodive");
  test::write_replay(dir / "out");
  const auto m = compute_metrics(read_replay_output(dir / "out"), nullptr, {});
  EXPECT_TRUE(m["dr_xy_rms_m"].is_null());
  EXPECT_TRUE(m["nees_mean"].is_null());
  EXPECT_TRUE(m["outliers_injected"].is_null());
  EXPECT_TRUE(m["realtime_factor"].is_null());
  EXPECT_EQ(m["images"], 40);  // proposals.csv rows
  EXPECT_DOUBLE_EQ(m["conservative_fraction"].get<double>(), 0.9);
  EXPECT_DOUBLE_EQ(m["wall_s"].get<double>(), 2.0);
}

}  // namespace
}  // namespace nav::report
