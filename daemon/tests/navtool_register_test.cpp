// Tests of `navtool register` (the built navtool binary, NAVTOOL_PATH) on the Sparus frames:
// the JSON object's fields, the Fig. 4 picture, a prior file, and clear errors for bad input.
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "nav/testing/data.h"

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

fs::path temp_dir() {
  const auto dir = fs::temp_directory_path() / ("navtool_register_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

RunResult run_navtool(const std::string& args) {
  const auto dir = temp_dir();
  const auto out = dir / "stdout", err = dir / "stderr";
  std::ostringstream command;
  command << '\'' << NAVTOOL_PATH << "' register " << args << " >'" << out.string() << "' 2>'"
          << err.string() << '\'';
  const int status = std::system(command.str().c_str());
  RunResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = slurp(out);
  result.err = slurp(err);
  return result;
}

fs::path write_file(const std::string& name, const std::string& text) {
  const fs::path path = temp_dir() / name;
  std::ofstream(path) << text;
  return path;
}

fs::path sparus_camera_yaml() {
  return write_file("sparus.yaml",
                    "camera:\n"
                    "  fx: 405.6384738851233\n"
                    "  fy: 405.588335378204\n"
                    "  cx: 189.9054317917407\n"
                    "  cy: 139.9149578253755\n"
                    "  distortion: [-0.3670656233416921, 0.203001968694465, "
                    "0.003336917744124004, -0.000487426354679637, 0.0]\n"
                    "  width: 384\n"
                    "  height: 288\n"
                    "  pixel_format: mono8\n");
}

/// 'path' built with a stream (GCC 12 -O3 reports a false -Wrestrict on std::string operator+
/// starting from a one-character literal).
std::string quoted(const fs::path& p) {
  std::ostringstream out;
  out << '\'' << p.string() << '\'';
  return out.str();
}

TEST(NavtoolRegister, SparusPairJsonHasEveryFieldAndDrawsTheFigure) {
  NAV_REQUIRE_DATA(frame1, "images/sparus/frame_01.png");
  const fs::path frame4 = frame1.parent_path() / "frame_04.png";
  const fs::path figure = temp_dir() / "fig4.png";
  const RunResult r = run_navtool(quoted(frame1) + " " + quoted(frame4) + " --camera " +
                                  quoted(sparus_camera_yaml()) + " --json --draw " + quoted(figure));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_TRUE(j.at("success").get<bool>()) << j.at("reason");
  EXPECT_EQ(j.at("measurement").size(), 5u);
  EXPECT_EQ(j.at("covariance").size(), 25u);
  EXPECT_GT(j.at("inliers").get<int>(), 100);
  EXPECT_GE(j.at("putative_matches").get<int>(), j.at("inliers").get<int>());
  EXPECT_GT(j.at("descriptor_comparisons").get<double>(), 1e5);
  for (const char* stage : {"features_i", "features_j", "matching", "essential", "total"}) {
    EXPECT_GT(j.at("ms").at(stage).get<double>(), 0.0) << stage;
  }
  // The relative roll/pitch/heading are a few degrees at most between frames 0.6 s apart.
  for (int k = 2; k < 5; ++k) EXPECT_LT(std::abs(j.at("measurement")[k].get<double>()), 0.1);
  ASSERT_TRUE(fs::exists(figure));
  EXPECT_GT(fs::file_size(figure), 10000u);
}

TEST(NavtoolRegister, PriorFileIsAccepted) {
  NAV_REQUIRE_DATA(frame1, "images/sparus/frame_01.png");
  const fs::path frame2 = frame1.parent_path() / "frame_02.png";
  std::ostringstream prior;
  prior << R"({"x_i_j": [0.0, -0.1, 0.0, 0.0, 0.0, 0.0], "covariance": [)";
  for (int k = 0; k < 36; ++k) prior << (k % 7 == 0 ? "0.01" : "0") << (k < 35 ? "," : "");
  prior << R"(], "scene_depth_m": 3.0, "scene_depth_sigma_m": 1.0})";
  const RunResult r = run_navtool(quoted(frame1) + " " + quoted(frame2) + " --camera " +
                                  quoted(sparus_camera_yaml()) + " --prior " +
                                  quoted(write_file("prior.json", prior.str())) + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_TRUE(j.contains("prior_chi2"));
  EXPECT_GT(j.at("putative_matches").get<int>(), 0);
}

TEST(NavtoolRegister, BadInputGivesAClearErrorAndExitStatus1) {
  NAV_REQUIRE_DATA(frame1, "images/sparus/frame_01.png");
  const std::string camera = " --camera " + quoted(sparus_camera_yaml());
  RunResult r = run_navtool(quoted(frame1) + " '/nonexistent/frame.png'" + camera);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("cannot read image /nonexistent/frame.png"), std::string::npos) << r.err;

  r = run_navtool(quoted(frame1) + " " + quoted(frame1) + " --camera " +
                  quoted(write_file("nocam.yaml", "sensors: []\n")));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no `camera:` block"), std::string::npos) << r.err;

  r = run_navtool(quoted(frame1) + " " + quoted(frame1) + " --camera " +
                  quoted(write_file("nofx.yaml", "camera:\n  fy: 400\n  cx: 190\n  cy: 140\n")));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("camera.fx is missing"), std::string::npos) << r.err;

  r = run_navtool(quoted(frame1) + " " + quoted(frame1) + camera + " --prior " +
                  quoted(write_file("bad_prior.json", R"({"x_i_j": [1, 2]})")));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("x_i_j needs 6 numbers"), std::string::npos) << r.err;

  // Wrong size against the calibration's 384x288.
  NAV_REQUIRE_DATA(skerki, "images/skerki/img_1.tif");
  r = run_navtool(quoted(skerki) + " " + quoted(skerki) + camera);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("calibration is for 384x288"), std::string::npos) << r.err;
}

}  // namespace
