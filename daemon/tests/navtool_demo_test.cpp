// Tests of `navtool demo` (the built navtool binary, NAVTOOL_PATH): the ESDF on the built-in
// simulated survey reports its summary keys, a final position error within 3 sigma, a sparse
// information matrix; bad options are refused.
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace {

using nlohmann::json;

struct RunResult {
  int exit_code = -1;
  std::string out, err;
};

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

RunResult run_navtool(const std::string& args) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("navtool_demo_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto out = dir / "stdout", err = dir / "stderr";
  const std::string command = std::string("'") + NAVTOOL_PATH + "' " + args + " >'" +
                              out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(command.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  std::filesystem::remove_all(dir);
  return r;
}

TEST(NavtoolDemo, JsonSummaryOfSmallSurvey) {
  const RunResult r = run_navtool("demo --images 40 --seed 3 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  for (const char* key :
       {"images", "states", "camera_links", "cross_track_links", "final_position_error_m",
        "final_position_3sigma_m", "final_pose_nees", "info_matrix_dim",
        "info_matrix_nonzero_fraction", "mean_predict_us", "mean_update_us"}) {
    EXPECT_TRUE(j.contains(key)) << "missing key " << key << " in " << r.out;
  }
  EXPECT_EQ(j["images"].get<int>(), 40);
  EXPECT_EQ(j["states"].get<int>(), 41);  // robot + one delayed state per image
  EXPECT_EQ(j["info_matrix_dim"].get<int>(), 41 * 12);
  EXPECT_GE(j["camera_links"].get<int>(), 39);  // at least the temporal chain
  EXPECT_GT(j["cross_track_links"].get<int>(), 0);
  const double err = j["final_position_error_m"].get<double>();
  const double three_sigma = j["final_position_3sigma_m"].get<double>();
  EXPECT_GT(three_sigma, 0.0);
  EXPECT_LE(err, three_sigma) << "final robot position error outside its 3-sigma";
  const double fill = j["info_matrix_nonzero_fraction"].get<double>();
  EXPECT_GT(fill, 0.0);
  EXPECT_LT(fill, 0.25);
  EXPECT_GT(j["mean_predict_us"].get<double>(), 0.0);
}

TEST(NavtoolDemo, HumanSummaryOnStderr) {
  const RunResult r = run_navtool("demo --images 10");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.out.empty()) << "stdout carries machine-readable output only";
  EXPECT_NE(r.err.find("final robot position error"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("images 10"), std::string::npos) << r.err;
}

TEST(NavtoolDemo, RejectsBadImageCount) {
  const RunResult r = run_navtool("demo --images 0 --json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_TRUE(r.out.empty());
  EXPECT_NE(r.err.find("images"), std::string::npos) << r.err;
}

}  // namespace
