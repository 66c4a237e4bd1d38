// Tests of `navtool report` (the built navtool binary, NAVTOOL_PATH) on the fixture dive and
// replay output of support/report_fixture.h: metrics.json with exact values, the four PNGs
// with the expected size and content, the dive directory taken from summary.json, missing
// optional files, and errors naming file:line with a non-zero exit status.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "nav/testing/data.h"
#include "support/navtool_run.h"
#include "support/report_fixture.h"

namespace {

namespace fs = std::filesystem;
using nav::tool::test::read_text;
using nav::tool::test::run_navtool;
using nlohmann::json;

/// Removes this process's temporary directories after the last test.
class RemoveTempDirs : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(
        fs::temp_directory_path() / ("navtool_report_test_" + std::to_string(::getpid())), ignored);
  }
};
[[maybe_unused]] ::testing::Environment* const kRemoveTempDirs =
    ::testing::AddGlobalTestEnvironment(new RemoveTempDirs);

fs::path fresh_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("navtool_report_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

/// `report 'out' --dive 'dive' rest` (built with a stream: GCC 12 -Wrestrict false positive).
std::string report_args(const fs::path& out, const fs::path& dive, const std::string& rest) {
  std::ostringstream s;
  s << "report '" << out.string() << "'";
  if (!dive.empty()) s << " --dive '" << dive.string() << "'";
  s << ' ' << rest;
  return s.str();
}

/// Fraction of pixels that are not white.
double ink_fraction(const cv::Mat& img) {
  int ink = 0;
  for (int r = 0; r < img.rows; ++r) {
    for (int c = 0; c < img.cols; ++c) {
      if (img.at<cv::Vec3b>(r, c) != cv::Vec3b(255, 255, 255)) ++ink;
    }
  }
  return static_cast<double>(ink) / img.total();
}

/// Pixels close to a BGR colour (the figure's data colours, report/plot.h).
int pixels_near(const cv::Mat& img, const cv::Vec3b& bgr) {
  int n = 0;
  for (int r = 0; r < img.rows; ++r) {
    for (int c = 0; c < img.cols; ++c) {
      const cv::Vec3b p = img.at<cv::Vec3b>(r, c);
      if (std::abs(p[0] - bgr[0]) + std::abs(p[1] - bgr[1]) + std::abs(p[2] - bgr[2]) < 30) ++n;
    }
  }
  return n;
}

TEST(NavtoolReport, FixtureGivesExactMetricsAndFourFigures) {
  const fs::path root = fresh_dir("full");
  nav::report::test::write_dive(root / "dive");
  nav::report::test::write_replay(root / "out");
  const auto r = run_navtool(report_args(root / "out", root / "dive", "--json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = json::parse(r.out);
  EXPECT_EQ(m, json::parse(read_text(root / "out/metrics.json")));
  for (const char* key :
       {"images", "camera_links", "links_proposed", "links_accepted", "outliers_injected",
        "outliers_rejected", "dr_xy_rms_m", "slam_xy_rms_m", "slam_final_xy_error_m", "nees_mean",
        "nees_95_interval", "conservative_fraction", "wall_s", "realtime_factor"}) {
    ASSERT_TRUE(m.contains(key)) << key;
    EXPECT_FALSE(m[key].is_null()) << key;
  }
  EXPECT_EQ(m["images"], 40);
  EXPECT_EQ(m["camera_links"], 5);
  EXPECT_EQ(m["links_proposed"], 10);
  EXPECT_EQ(m["links_accepted"], 6);
  EXPECT_EQ(m["outliers_injected"], 4);
  EXPECT_EQ(m["outliers_rejected"], 2);
  EXPECT_NEAR(m["dr_xy_rms_m"].get<double>(), 2.0, 1e-12);
  EXPECT_NEAR(m["slam_xy_rms_m"].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(m["slam_final_xy_error_m"].get<double>(), 1.0, 1e-12);
  // The robot pose (newest state, frame 39) is one chi2(6) sample: its interval, not one of N.
  EXPECT_EQ(m["nees_samples"], 1);
  EXPECT_EQ(m["nees_robot_pose"]["frame_id"], nav::report::test::kImages - 1);
  EXPECT_DOUBLE_EQ(m["nees_mean"].get<double>(), m["nees_robot_pose"]["nees"].get<double>());
  EXPECT_NEAR(m["nees_95_interval"][0].get<double>(), 1.23734, 1e-4);
  EXPECT_NEAR(m["nees_95_interval"][1].get<double>(), 14.44938, 1e-4);
  EXPECT_GT(m["nees_mean"].get<double>(), m["nees_95_interval"][0].get<double>());
  EXPECT_LT(m["nees_mean"].get<double>(), m["nees_95_interval"][1].get<double>());
  EXPECT_EQ(m["nees_all_states_diagnostic"]["states"], nav::report::test::kImages);
  EXPECT_FALSE(m["nees_all_states_diagnostic"].contains("interval_95"));
  EXPECT_DOUBLE_EQ(m["conservative_fraction"].get<double>(), 0.9);
  EXPECT_DOUBLE_EQ(m["wall_s"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(m["realtime_factor"].get<double>(), 80.0);  // sim.json duration 160 s / 2 s
  EXPECT_EQ(m["information_matrix"]["dim"], 246);
  EXPECT_NEAR(m["information_matrix"]["nonzero_fraction"].get<double>(),
              36.0 * (41 + 2 * 45) / (246.0 * 246.0), 1e-12);
  EXPECT_DOUBLE_EQ(m["logdet_ratio_ours"]["nonnegative_fraction"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(m["logdet_ratio_markov_blanket"]["nonnegative_fraction"].get<double>(), 0.0);
  EXPECT_EQ(m["figures"].size(), 4u);
  // time_of_use.csv: Fig. 3 at the time of use; its figure stays at the end of the dive, as one
  // row has no Markov-blanket value.
  EXPECT_EQ(m["time_of_use_checks"], 2);
  EXPECT_DOUBLE_EQ(m["time_of_use_conservative_fraction"].get<double>(), 1.0);
  EXPECT_EQ(m["logdet_ratio_relative_ours"]["count"], 9);
  EXPECT_NEAR(m["logdet_ratio_relative_ours"]["median"].get<double>(), 0.4, 1e-12);
  EXPECT_NEAR(m["logdet_ratio_relative_ours"]["max"].get<double>(), 0.8, 1e-12);
  EXPECT_EQ(m["logdet_ratio_relative_markov_blanket"]["count"], 8);
  EXPECT_DOUBLE_EQ(m["logdet_ratio_relative_markov_blanket"]["median"].get<double>(), -1.0);
  EXPECT_EQ(m["fig3_values"], "at the end of the dive");

  for (const char* png : {"fig1_trajectory.png", "fig2_sparsity.png", "fig3_logdet_histogram.png",
                          "fig5_network.png"}) {
    const cv::Mat img = cv::imread((root / "out" / png).string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(img.empty()) << png;
    EXPECT_EQ(img.cols, 1000) << png;
    EXPECT_EQ(img.rows, 800) << png;
    const double ink = ink_fraction(img);
    EXPECT_GT(ink, 0.01) << png;  // axes, text and data, not a blank canvas
    EXPECT_LT(ink, 0.6) << png;
  }
  // Data drawn, not only axes: the colours of report/plot.h.
  const cv::Vec3b blue(200, 90, 20), red(40, 40, 220), orange(0, 140, 255), magenta(180, 40, 180);
  EXPECT_GT(pixels_near(cv::imread((root / "out/fig1_trajectory.png").string()), red), 200);
  EXPECT_GT(pixels_near(cv::imread((root / "out/fig2_sparsity.png").string()), blue), 5000);
  const cv::Mat fig3 = cv::imread((root / "out/fig3_logdet_histogram.png").string());
  EXPECT_GT(pixels_near(fig3, orange), 2000);
  EXPECT_GT(pixels_near(fig3, blue), 2000);
  EXPECT_GT(pixels_near(cv::imread((root / "out/fig5_network.png").string()), magenta), 500);
}

TEST(NavtoolReport, DiveDirectoryComesFromSummaryJson) {
  const fs::path root = fresh_dir("summary_dive");
  nav::report::test::write_dive(root / "dive");
  nav::report::test::ReplayFixtureOptions o;
  o.dive_dir = (root / "dive").string();
  nav::report::test::write_replay(root / "out", o);
  const auto r = run_navtool(report_args(root / "out", {}, "--json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = json::parse(r.out);
  EXPECT_EQ(m["inputs"]["dive_dir"], (root / "dive").string());
  EXPECT_NEAR(m["slam_xy_rms_m"].get<double>(), 1.0, 1e-12);
}

TEST(NavtoolReport, Fig3ComesFromTheTimeOfUseWhenEveryCheckHasTheMarkovBlanket) {
  const fs::path root = fresh_dir("time_of_use");
  nav::report::test::write_dive(root / "dive");
  nav::report::test::write_replay(root / "out");
  {
    std::ofstream tou(root / "out/time_of_use.csv");
    tou << "frame_id,state,ours,markov_blanket\n10,1,0.5,-1.5\n10,2,0.25,-0.5\n";
  }
  const auto r = run_navtool(report_args(root / "out", root / "dive", "--json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = json::parse(r.out);
  EXPECT_EQ(m["fig3_values"], "at the time of use (2 checks)");
  EXPECT_DOUBLE_EQ(m["logdet_ratio_relative_markov_blanket"]["median"].get<double>(), -1.0);
  EXPECT_TRUE(fs::exists(root / "out/fig3_logdet_histogram.png"));
}

TEST(NavtoolReport, WithoutDiveAndOptionalFilesMetricsAreNullAndFiguresSkipped) {
  const fs::path root = fresh_dir("minimal");
  nav::report::test::ReplayFixtureOptions o;
  o.with_initial_bound = false;
  o.with_optional_files = false;
  nav::report::test::write_replay(root / "out", o);
  const auto r = run_navtool(report_args(root / "out", {}, "--json"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json m = json::parse(r.out);
  EXPECT_TRUE(m["slam_xy_rms_m"].is_null());
  EXPECT_TRUE(m["nees_mean"].is_null());
  EXPECT_TRUE(m["logdet_ratio_relative_ours"].is_null());
  EXPECT_EQ(m["time_of_use_checks"], 0);
  EXPECT_EQ(m["fig3_values"], "none");
  EXPECT_FALSE(m["fig5_initial_bound_present"].get<bool>());
  EXPECT_TRUE(m["figures_skipped"].contains("fig2_sparsity.png"));
  EXPECT_TRUE(m["figures_skipped"].contains("fig3_logdet_histogram.png"));
  EXPECT_TRUE(fs::exists(root / "out/fig1_trajectory.png"));
  EXPECT_TRUE(fs::exists(root / "out/fig5_network.png"));
  EXPECT_FALSE(fs::exists(root / "out/fig2_sparsity.png"));
}

TEST(NavtoolReport, NonNumericCellIsAnErrorNamingFileLineAndColumn) {
  const fs::path root = fresh_dir("bad_number");
  nav::report::test::write_dive(root / "dive");
  nav::report::test::write_replay(root / "out");
  std::string traj = read_text(root / "out/trajectory.csv");
  // Line 4 (third data row): replace its x_m value with text.
  size_t at = 0;
  for (int k = 0; k < 3; ++k) at = traj.find('\n', at) + 1;
  const size_t comma = traj.find(',', at);
  traj.replace(comma + 1, traj.find(',', comma + 1) - comma - 1, "north");
  nav::report::test::write_file(root / "out/trajectory.csv", traj);
  const auto r = run_navtool(report_args(root / "out", root / "dive", "--json"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("trajectory.csv:4: column 'x_m': 'north' is not a finite number"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(r.out.empty());
}

TEST(NavtoolReport, MissingColumnIsAnErrorNamingFileAndColumn) {
  const fs::path root = fresh_dir("missing_column");
  nav::report::test::write_dive(root / "dive");
  nav::report::test::write_replay(root / "out");
  std::string truth = read_text(root / "dive/truth.csv");
  truth.replace(truth.find("y_m"), 3, "east");
  nav::report::test::write_file(root / "dive/truth.csv", truth);
  const auto r = run_navtool(report_args(root / "out", root / "dive", ""));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("truth.csv: missing column 'y_m'"), std::string::npos) << r.err;
}

TEST(NavtoolReport, ShortRowAndMissingFileAreErrors) {
  const fs::path root = fresh_dir("short_row");
  nav::report::test::write_replay(root / "out");
  nav::report::test::write_file(root / "out/links.csv",
                                std::string(nav::report::test::kLinks) + "1,2,3\n");
  auto r = run_navtool(report_args(root / "out", {}, ""));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("links.csv:12: 3 fields, header has 8"), std::string::npos) << r.err;
  fs::remove(root / "out/links.csv");
  r = run_navtool(report_args(root / "out", {}, ""));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("links.csv: cannot open"), std::string::npos) << r.err;
}

}  // namespace

namespace {

TEST(NavtoolCovarianceFigure, WritesTheFig3HistogramOfAPoseGraph) {
  NAV_REQUIRE_DATA(graph, "posegraphs/tinyGrid3D.g2o");
  const fs::path root = fresh_dir("covariance_figure");
  std::ostringstream args;
  args << "covariance '" << graph.string() << "' --json --direct --figure '"
       << (root / "fig3.png").string() << "'";
  const auto r = run_navtool(args.str());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json out = json::parse(r.out);
  EXPECT_EQ(out["figure"], (root / "fig3.png").string());
  const cv::Mat img = cv::imread((root / "fig3.png").string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 1000);
  EXPECT_EQ(img.rows, 800);
  EXPECT_GT(pixels_near(img, cv::Vec3b(200, 90, 20)), 500);  // ours: blue bars
  // An unwritable path is an error naming it.
  std::ostringstream bad;
  bad << "covariance '" << graph.string() << "' --direct --figure '"
      << (root / "no/such/dir/fig3.png").string() << "'";
  const auto e = run_navtool(bad.str());
  EXPECT_NE(e.exit_code, 0);
  EXPECT_NE(e.err.find("no/such/dir/fig3.png"), std::string::npos) << e.err;
}

}  // namespace
