// Tests of `navtool covariance` (the built navtool binary, NAVTOOL_PATH): JSON report on real
// pose graphs, every bound conservative, and clear errors naming the line or vertex for
// malformed input (small temporary files).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>

#include "nav/testing/data.h"

namespace {

using nlohmann::json;

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("navtool_covariance_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

RunResult run_navtool(const std::string& args) {
  const auto dir = temp_dir();
  const auto out = dir / "stdout", err = dir / "stderr";
  const std::string command = std::string("'") + NAVTOOL_PATH + "' covariance " + args + " >'" +
                              out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(command.c_str());
  RunResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = slurp(out);
  result.err = slurp(err);
  return result;
}

/// `'path' rest` built with a stream (GCC 12 -O3 reports a false -Wrestrict on chained
/// std::string operator+ starting from a one-character literal).
std::string args_for(const std::string& path, const std::string& rest) {
  std::ostringstream out;
  out << '\'' << path << "' " << rest;
  return out.str();
}

/// Writes `text` to a temporary .g2o file and returns its path.
std::string write_graph(const std::string& name, const std::string& text) {
  const auto path = temp_dir() / name;
  std::ofstream(path) << text;
  return path.string();
}

const char* kInfo = " 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1";
const std::string kVertices =
    "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n"
    "VERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n"
    "VERTEX_SE3:QUAT 2 2 0 0 0 0 0 1\n";

TEST(NavtoolCovariance, TinyGridJsonReportHasEveryFieldAndConservativeBounds) {
  NAV_REQUIRE_DATA(path, "posegraphs/tinyGrid3D.g2o");
  for (const std::string mode : {"--direct", "--iterations 2", "--tolerance 1e-10"}) {
    std::string rest = "--json ";
    rest += mode;
    const RunResult r = run_navtool(args_for(path.string(), rest));
    ASSERT_EQ(r.exit_code, 0) << mode << ": " << r.err;
    const json j = json::parse(r.out);
    for (const char* key :
         {"poses", "edges", "state_dim", "nnz_fraction", "steps", "recovery_ms_median",
          "recovery_ms_p99", "bounds_update_us_median", "exact_marginals_ms",
          "max_relative_residual", "conservative_fraction", "conservative_checked",
          "logdet_ratio_ours", "logdet_ratio_markov_blanket",
          "markov_blanket_overconfident_fraction", "peak_rss_mb", "fig3_histogram"}) {
      EXPECT_TRUE(j.contains(key)) << mode << ": missing " << key;
    }
    EXPECT_EQ(j["poses"], 9);
    EXPECT_EQ(j["edges"], 11);
    EXPECT_EQ(j["state_dim"], 54);
    EXPECT_EQ(j["steps"], 8);
    EXPECT_EQ(j["conservative_checked"], 9);
    EXPECT_EQ(j["conservative_fraction"], 1.0) << mode;
    EXPECT_GE(j["logdet_ratio_ours"]["min"].get<double>(), -1e-6) << mode;
    EXPECT_GT(j["peak_rss_mb"].get<double>(), 0.0);
    const json& h = j["fig3_histogram"];
    EXPECT_EQ(h["bin_edges"].size(), h["ours"].size() + 1);
  }
}

TEST(NavtoolCovariance, SmallGridFixedBudgetStaysConservative) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  const RunResult r = run_navtool(args_for(path.string(), "--json --iterations 1"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["conservative_checked"], 125);
  EXPECT_EQ(j["conservative_fraction"], 1.0);
  EXPECT_GT(j["markov_blanket_overconfident_fraction"].get<double>(), 0.5);
}

TEST(NavtoolCovariance, KeptFactorIsTightAndConservativeAtTheTimeOfUse) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  const RunResult r = run_navtool(args_for(
      path.string(), "--json --preconditioner kept-factor --refresh-interval 10 --checks 20"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["kept_factor"], true);
  EXPECT_EQ(j["iterations_median"], 1.0);  // M = Λ: one iteration is the direct solve
  EXPECT_EQ(j["refreshes"], 13);           // 124 steps, the interval only
  EXPECT_EQ(j["conservative_fraction"], 1.0);
  EXPECT_EQ(j["time_of_use_conservative_fraction"], 1.0);
  EXPECT_EQ(j["time_of_use_joint_conservative_fraction"], 1.0);
  EXPECT_LT(j["logdet_ratio_relative_ours"]["median"].get<double>(), 1.0);
}

TEST(NavtoolCovariance, DefaultsAreTheKeptFactorWithExactMarginalsEveryTwentySteps) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  const RunResult r = run_navtool(args_for(path.string(), "--json --checks 10"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["kept_factor"], true);
  EXPECT_EQ(j["refreshes"], 7);  // 124 steps: the first and every 20th
  EXPECT_EQ(j["time_of_use_conservative_fraction"], 1.0);
  EXPECT_EQ(j["time_of_use_joint_conservative_fraction"], 1.0);
  // --preconditioner factor keeps its own default: a refactorisation at every step.
  const RunResult f =
      run_navtool(args_for(path.string(), "--json --checks 0 --preconditioner factor"));
  ASSERT_EQ(f.exit_code, 0) << f.err;
  EXPECT_EQ(json::parse(f.out)["refreshes"], 124);
}

TEST(NavtoolCovariance, ToleranceModeAtTheIterationCapSucceedsAndCountsTheCappedSteps) {
  NAV_REQUIRE_DATA(path, "posegraphs/smallGrid3D.g2o");
  const RunResult r =
      // The stale factor's steps between refreshes (a refreshed step, and every step of the
      // kept factor, is the direct solve, at the rounding floor at once).
      run_navtool(args_for(path.string(),
                           "--json --tolerance 1e-15 --max-iterations 2 --preconditioner factor "
                           "--refresh-interval 10"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["mode"], "tolerance");
  EXPECT_EQ(j["max_iterations_per_step"], 2);
  EXPECT_EQ(j["relative_tolerance"].get<double>(), 1e-15);
  EXPECT_GT(j["capped_steps"].get<int>(), 100);
  EXPECT_LE(j["capped_steps"].get<int>(), j["steps"].get<int>());
  EXPECT_GT(j["max_relative_residual"].get<double>(), 1e-6);
  EXPECT_GE(j["max_relative_residual"].get<double>(),
            j["relative_residual_median"].get<double>());
  EXPECT_EQ(j["conservative_checked"], 125);
  EXPECT_EQ(j["conservative_fraction"], 1.0);
  // --max-iterations only means something with --tolerance.
  EXPECT_NE(run_navtool(args_for(path.string(), "--json --max-iterations 2")).exit_code, 0);
}

/// A planar g2o graph (VERTEX_SE2 / EDGE_SE2, with a FIX line as many such files have): a
/// 6 x 6 lattice walked row by row, odometry between consecutive poses and a loop closure to
/// the pose below in the previous row, measurements perturbed deterministically.
std::string planar_lattice() {
  std::ostringstream g;
  g << "FIX 0\n";
  constexpr int kSide = 6;
  auto xy = [](int k) {
    const int row = k / kSide, col = row % 2 == 0 ? k % kSide : kSide - 1 - k % kSide;
    return std::pair<double, double>{col, row};
  };
  for (int k = 0; k < kSide * kSide; ++k) {
    g << "VERTEX_SE2 " << k << " " << xy(k).first << " " << xy(k).second << " 0\n";
  }
  auto edge = [&](int i, int j) {
    const double noise = 0.02 * std::sin(7.0 * i + 3.0 * j);
    g << "EDGE_SE2 " << i << " " << j << " " << xy(j).first - xy(i).first + noise << " "
      << xy(j).second - xy(i).second - noise << " " << 0.5 * noise << " 400 20 0 300 -10 2500\n";
  };
  for (int k = 1; k < kSide * kSide; ++k) {
    edge(k - 1, k);
    const int row = k / kSide;
    if (row == 0) continue;
    for (int i = (row - 1) * kSide; i < row * kSide; ++i) {
      if (xy(i).first == xy(k).first && i != k - 1) edge(i, k);
    }
  }
  return g.str();
}

TEST(NavtoolCovariance, PlanarGraphIsLiftedAndItsBoundsAreConservative) {
  const std::string file = write_graph("planar.g2o", planar_lattice());
  const RunResult r = run_navtool(args_for(file, "--json --checks 10"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["planar"], true);
  EXPECT_EQ(j["poses"], 36);
  EXPECT_EQ(j["edges"], 35 + 30 - 5);  // odometry, and one closure per pose above row 0 but
                                       // the row's first, whose lower neighbour is its odometry
  EXPECT_EQ(j["state_dim"], 216);
  EXPECT_EQ(j["conservative_fraction"], 1.0);
  EXPECT_EQ(j["time_of_use_conservative_fraction"], 1.0);
  EXPECT_EQ(j["time_of_use_joint_conservative_fraction"], 1.0);
  EXPECT_LT(j["logdet_ratio_relative_ours"]["median"].get<double>(), 1.0);
}

TEST(NavtoolCovariance, ChainGraphWithLoopClosure) {
  const std::string file = write_graph(
      "chain.g2o", kVertices + "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1" + kInfo +
                       "\nEDGE_SE3:QUAT 1 2 1 0 0 0 0 0 1" + kInfo +
                       "\nEDGE_SE3:QUAT 0 2 2 0 0 0 0 0 1" + kInfo + "\n");
  const RunResult r = run_navtool(args_for(file, "--json --iterations 3"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["steps"], 2);
  EXPECT_EQ(j["broken_chain_vertices"], 0);
  EXPECT_EQ(j["conservative_fraction"], 1.0);
}

TEST(NavtoolCovariance, BrokenChainUsesAnotherEdgeAndSaysSoInHelp) {
  const std::string file = write_graph(
      "broken.g2o", kVertices + "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1" + kInfo +
                        "\nEDGE_SE3:QUAT 0 2 2 0 0 0 0 0 1" + kInfo + "\n");
  const RunResult r = run_navtool(args_for(file, "--json --direct"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out)["broken_chain_vertices"], 1);
  const RunResult help = run_navtool("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("Broken odometry chain"), std::string::npos) << help.out;
}

TEST(NavtoolCovariance, VertexWithoutEarlierEdgeIsAnErrorNamingIt) {
  const std::string file =
      write_graph("orphan.g2o", kVertices + "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1" + kInfo + "\n");
  const RunResult r = run_navtool(args_for(file, "--json"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(r.out.empty());
  EXPECT_NE(r.err.find("vertex 2"), std::string::npos) << r.err;
}

TEST(NavtoolCovariance, MalformedLinesAreErrorsNamingTheLine) {
  struct Case {
    const char* name;
    std::string text;
    const char* expect;  // substring of the error
    const char* alternative = nullptr;  // the reader or the replay may catch it
  };
  const Case cases[] = {
      {"unknown_tag.g2o", kVertices + "VERTEX_XY 3 0 0\n", ":4:"},
      {"short_edge.g2o", kVertices + "EDGE_SE3:QUAT 0 1 1 0 0\n", ":4:"},
      {"bad_number.g2o", "VERTEX_SE3:QUAT 0 0 zero 0 0 0 0 1\n", ":1:"},
      {"bad_info.g2o",
       kVertices + "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 -1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n"
                   "EDGE_SE3:QUAT 1 2 1 0 0 0 0 0 1" + kInfo + "\n",
       "line 4", ":4:"},
  };
  for (const Case& c : cases) {
    const RunResult r = run_navtool(args_for(write_graph(c.name, c.text), "--json"));
    EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.err;
    EXPECT_TRUE(r.out.empty()) << c.name;
    const bool named = r.err.find(c.expect) != std::string::npos ||
                       (c.alternative != nullptr && r.err.find(c.alternative) != std::string::npos);
    EXPECT_TRUE(named) << c.name << ": " << r.err;
  }
  const RunResult missing = run_navtool("/nonexistent/graph.g2o --json");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("/nonexistent/graph.g2o"), std::string::npos) << missing.err;
  // Modes are exclusive.
  const RunResult both = run_navtool("x.g2o --direct --iterations 3");
  EXPECT_NE(both.exit_code, 0);
}

}  // namespace
