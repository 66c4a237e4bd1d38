// navtool replay end to end: simulate a small dive (navtool simulate), replay it as fast as
// possible, check the summary, every replay output file, the SLAM estimate against the
// simulator's truth within 3 sigma of the exact marginal, conservative bounds, outliers gated,
// and determinism (two replays give identical files).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "support/navtool_run.h"

namespace nav::tool::test {
namespace {

namespace fs = std::filesystem;

std::vector<double> numbers_of(const std::string& line) {
  std::vector<double> v;
  std::stringstream ss(line);
  for (std::string cell; std::getline(ss, cell, ',');) v.push_back(cell.empty() ? NAN : std::atof(cell.c_str()));
  return v;
}

/// Time-of-use checks at images 0, 7, ..., 35 of the 40, with the Markov blanket.
constexpr const char* kTimeOfUse = " --time-of-use-every 7 --time-of-use-markov-blanket";
constexpr int kTimeOfUseChecks = 6;

class NavtoolReplay : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() / ("navtool_replay_" + std::to_string(::getpid())));
    fs::create_directories(*root_);
    const NavtoolOutput sim = run_navtool("simulate --out '" + (*root_ / "dive").string() +
                                          "' --images 40 --seed 3 --outlier-rate 0.2 --json");
    ASSERT_EQ(sim.exit_code, 0) << sim.err;
    sim_ = new nlohmann::json(nlohmann::json::parse(sim.out));
    const NavtoolOutput replay = run_navtool("replay '" + (*root_ / "dive").string() +
                                             "' --as-fast-as-possible --json --out '" +
                                             (*root_ / "out").string() + "'" + kTimeOfUse);
    ASSERT_EQ(replay.exit_code, 0) << replay.err;
    summary_ = new nlohmann::json(nlohmann::json::parse(replay.out));
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    if (root_) fs::remove_all(*root_, ignored);
    delete root_;
    delete sim_;
    delete summary_;
  }
  static fs::path* root_;
  static nlohmann::json* sim_;
  static nlohmann::json* summary_;
};
fs::path* NavtoolReplay::root_ = nullptr;
nlohmann::json* NavtoolReplay::sim_ = nullptr;
nlohmann::json* NavtoolReplay::summary_ = nullptr;

TEST_F(NavtoolReplay, SummaryCountsEveryImageAndGatesOutliers) {
  ASSERT_NE(summary_, nullptr);
  const nlohmann::json& s = *summary_;
  EXPECT_EQ(s["error"], "");
  EXPECT_EQ(s["images"], (*sim_)["images"]);
  EXPECT_EQ(s["delayed_states"], s["images"]);
  for (const char* key : {"camera_links", "wall_s", "realtime_factor", "final_pose",
                          "max_cg_relative_residual", "links_proposed", "links_accepted",
                          "outliers_rejected", "conservative_fraction"}) {
    EXPECT_TRUE(s.contains(key)) << key;
  }
  EXPECT_GT(s["links_accepted"].get<int>(), 40);
  EXPECT_DOUBLE_EQ(s["conservative_fraction"].get<double>(), 1.0);
  EXPECT_EQ(s["decode_errors"], 0);
  // Outliers that reached the gate: all rejected (the simulator's are gross).
  EXPECT_GT(s["outliers_rejected"].get<int>(), 0);
  EXPECT_EQ(s["outliers_accepted"], 0);
}

TEST_F(NavtoolReplay, FinalStatesWithinThreeSigmaOfTruth) {
  ASSERT_NE(summary_, nullptr);
  // images.csv: frame_id,t_us,x_m,y_m,... truth per frame.
  std::map<long, std::vector<double>> truth;
  const auto image_lines = lines_of(read_text(*root_ / "dive" / "images.csv"));
  for (size_t k = 1; k < image_lines.size(); ++k) {
    const auto v = numbers_of(image_lines[k]);
    truth[static_cast<long>(v[0])] = v;
  }
  const auto state_lines = lines_of(read_text(*root_ / "out" / "states.csv"));
  ASSERT_GE(state_lines.size(), truth.size());
  int outside = 0;
  for (size_t k = 1; k < state_lines.size(); ++k) {
    const auto v = numbers_of(state_lines[k]);
    ASSERT_EQ(v.size(), 9u + 3 * 36u);
    const auto& t = truth.at(static_cast<long>(v[1]));
    // exact marginal e00 (x), e11 (y): columns 9 + 36 + 0 and 9 + 36 + 7.
    const double ex = (v[3] - t[2]) / std::sqrt(v[45]), ey = (v[4] - t[3]) / std::sqrt(v[52]);
    if (std::abs(ex) > 3.0 || std::abs(ey) > 3.0) ++outside;
  }
  // The last state in particular, and at most a few percent of all.
  const auto last = numbers_of(state_lines.back());
  const auto& t_last = truth.at(static_cast<long>(last[1]));
  EXPECT_LT(std::hypot(last[3] - t_last[2], last[4] - t_last[3]),
            3.0 * std::sqrt(last[45] + last[52]));
  EXPECT_LE(outside, 2);
}

TEST_F(NavtoolReplay, WritesEveryOutputFile) {
  ASSERT_NE(summary_, nullptr);
  const fs::path out = *root_ / "out";
  const std::map<std::string, std::string> headers = {
      {"trajectory.csv", "t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad,var_x,var_y,var_z,var_heading"},
      {"dead_reckoning.csv", "t_us,x_m,y_m,z_m,roll_rad,pitch_rad,heading_rad,var_x,var_y,var_z,var_heading"},
      {"links.csv", "t_us,frame_i,frame_j,state_i,state_j,outcome,mahalanobis_sq,is_outlier"},
      {"proposals.csv",
       "frame_id,candidates,proposed,accepted,true_overlapping,true_overlapping_proposed"},
      {"logdet.csv", "state_i,state_j,ours,markov_blanket"},
  };
  const int images = (*summary_)["images"];
  for (const auto& [file, header] : headers) {
    const auto lines = lines_of(read_text(out / file));
    ASSERT_FALSE(lines.empty()) << file;
    EXPECT_EQ(lines[0], header) << file;
  }
  EXPECT_EQ(lines_of(read_text(out / "trajectory.csv")).size(), static_cast<size_t>(images + 1));
  EXPECT_EQ(lines_of(read_text(out / "proposals.csv")).size(), static_cast<size_t>(images + 1));
  EXPECT_EQ(lines_of(read_text(out / "logdet.csv")).size(), static_cast<size_t>(images + 1));
  const auto links = lines_of(read_text(out / "links.csv"));
  EXPECT_EQ(links.size(), (*summary_)["links_proposed"].get<size_t>() + 1);
  for (size_t k = 1; k < links.size(); ++k) {
    EXPECT_EQ(links[k].find(",-1,"), std::string::npos) << "state_j not filled: " << links[k];
  }
  const auto blocks = lines_of(read_text(out / "information_blocks.csv"));
  ASSERT_GE(blocks.size(), 2u);
  EXPECT_EQ(blocks[0], "# block_dim 12 num_blocks " + std::to_string(images + 1));
  EXPECT_EQ(read_text(out / "summary.json").find("\"conservative_fraction\"") != std::string::npos,
            true);
}

TEST_F(NavtoolReplay, ProposesOverlappingPairsWithinTheBudgetAndPublishesAnHonestCovariance) {
  ASSERT_NE(summary_, nullptr);
  const nlohmann::json& s = *summary_;
  // config/sim.yaml keeps the default budget of 15 pairs per image.
  ASSERT_TRUE(s["proposals_per_image_mean"].is_number());
  EXPECT_GT(s["proposals_per_image_mean"].get<double>(), 1.0);
  EXPECT_LE(s["proposals_per_image_mean"].get<double>(), 15.0);
  ASSERT_TRUE(s["proposal_recall"].is_number()) << "the oracle states true overlaps";
  // Below 1: some images overlap more than 15 earlier ones by >= 20 % (docs/performance.md).
  EXPECT_GE(s["proposal_recall"].get<double>(), 0.8);
  // proposals.csv: the per-image counts behind the recall; never more than 15 proposed.
  long overlapping = 0, found = 0;
  const auto rows = lines_of(read_text(*root_ / "out" / "proposals.csv"));
  for (size_t k = 1; k < rows.size(); ++k) {
    const auto v = numbers_of(rows[k]);
    ASSERT_EQ(v.size(), 6u);
    EXPECT_LE(v[2], 15.0);
    EXPECT_LE(v[5], v[4]);
    overlapping += static_cast<long>(v[4]);
    found += static_cast<long>(v[5]);
  }
  ASSERT_GT(overlapping, 0);
  EXPECT_DOUBLE_EQ(s["proposal_recall"].get<double>(), static_cast<double>(found) / overlapping);
  // published.csv: one row per 0.1 s of data time (nav_solution at 10 Hz), NEES against truth
  // (chi2(6): mean 6, 1 % above 16.81; this short dive's first turn leaves the estimate off by
  // more than its covariance, docs/consistency.md, hence the loose limits).
  const auto published = lines_of(read_text(*root_ / "out" / "published.csv"));
  EXPECT_GT(published.size(), 10u * (*sim_)["images"].get<size_t>());
  ASSERT_TRUE(s["published_nees_mean"].is_number());
  EXPECT_GT(s["published_nees_mean"].get<double>(), 0.5);
  EXPECT_LT(s["published_nees_mean"].get<double>(), 30.0);
  EXPECT_LT(s["published_nees_exceed_99_fraction"].get<double>(), 0.6);
}

TEST_F(NavtoolReplay, ChecksTheBoundsAtTheTimeOfUse) {
  ASSERT_NE(summary_, nullptr);
  const nlohmann::json& s = *summary_;
  EXPECT_EQ(s["time_of_use_checks"], kTimeOfUseChecks);
  EXPECT_DOUBLE_EQ(s["time_of_use_conservative_fraction"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(s["time_of_use_joint_conservative_fraction"].get<double>(), 1.0);
  EXPECT_GT(s["time_of_use_s"].get<double>(), 0.0);
  // Ours is conservative, the Markov blanket over-confident (paper Fig. 3).
  EXPECT_GE(s["logdet_ratio_relative_ours_median"].get<double>(), 0.0);
  EXPECT_LT(s["logdet_ratio_relative_markov_blanket_median"].get<double>(), 0.0);
  // time_of_use.csv: per check, the delayed states 1..n of that moment, in order.
  const auto rows = lines_of(read_text(*root_ / "out" / "time_of_use.csv"));
  ASSERT_GT(rows.size(), 1u);
  EXPECT_EQ(rows[0], "frame_id,state,ours,markov_blanket");
  std::map<long, std::vector<long>> states_by_frame;
  for (size_t k = 1; k < rows.size(); ++k) {
    const auto v = numbers_of(rows[k]);
    ASSERT_EQ(v.size(), 4u) << rows[k];
    states_by_frame[static_cast<long>(v[0])].push_back(static_cast<long>(v[1]));
    EXPECT_GE(v[2], -1e-6) << rows[k];
    EXPECT_FALSE(std::isnan(v[3])) << rows[k];
  }
  // The first check, at image 0, has no delayed state yet.
  EXPECT_EQ(states_by_frame.size(), static_cast<size_t>(kTimeOfUseChecks - 1));
  size_t previous = 0;
  for (const auto& [frame, states] : states_by_frame) {
    for (size_t k = 0; k < states.size(); ++k) EXPECT_EQ(states[k], static_cast<long>(k + 1));
    EXPECT_GT(states.size(), previous) << "frame " << frame;
    previous = states.size();
  }
}

TEST_F(NavtoolReplay, IsDeterministic) {
  ASSERT_NE(summary_, nullptr);
  const NavtoolOutput again = run_navtool("replay '" + (*root_ / "dive").string() +
                                          "' --as-fast-as-possible --out '" +
                                          (*root_ / "again").string() + "'" + kTimeOfUse);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  for (const char* file :
       {"trajectory.csv", "states.csv", "links.csv", "logdet.csv", "proposals.csv", "published.csv",
        "time_of_use.csv"}) {
    EXPECT_EQ(read_text(*root_ / "out" / file), read_text(*root_ / "again" / file)) << file;
  }
}

TEST(NavtoolReplayErrors, MissingLogIsAnError) {
  const NavtoolOutput r = run_navtool("replay /nonexistent/dive --as-fast-as-possible");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no dive log at /nonexistent/dive"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace nav::tool::test
