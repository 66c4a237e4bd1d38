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

#include <Eigen/Geometry>
#include <cstdio>
#include <vector>

#include "nav/core/geometry/rotation.h"
#include "nav/core/models/binary_models.h"
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

/// Rows of a simulated dive's images.csv: frame id and the vehicle pose [x y z r p h] (NED, rad)
/// with the altitude.
struct ImageRow {
  int frame = 0;
  nav::core::Vec6 pose = nav::core::Vec6::Zero();
  double altitude_m = 0.0;
};

std::vector<ImageRow> read_images_csv(const fs::path& path) {
  std::vector<ImageRow> rows;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(ss, cell, ',')) v.push_back(std::stod(cell));
    if (v.size() < 9) continue;
    ImageRow row;
    row.frame = static_cast<int>(v[0]);
    row.pose << v[2], v[3], v[4], v[5], v[6], v[7];
    row.altitude_m = v[8];
    rows.push_back(row);
  }
  return rows;
}

TEST(NavtoolRegister, SimulatorRenderedMono12PairsWithTruthPriorMatchTheTruth) {
  // A short simulated dive with rendered 12-bit frames (config/sim.yaml's camera: fx = fy =
  // 1000, 1280x1024 Mono12, mount [1 0 0.5] m, heading 90 deg), registered with a prior at the
  // true relative camera pose: the pose-constrained search compares far fewer descriptors than
  // |i| x |j| and the measured rotation matches the truth.
  const fs::path dive = temp_dir() / "dive";
  fs::remove_all(dive);
  std::ostringstream simulate;
  simulate << '\'' << NAVTOOL_PATH << "' simulate --out '" << dive.string()
           << "' --images 6 --render-images --config '" << NAV_SOURCE_DIR
           << "/config/sim.yaml' >/dev/null 2>&1";
  ASSERT_EQ(std::system(simulate.str().c_str()), 0);
  const std::vector<ImageRow> rows = read_images_csv(dive / "images.csv");
  ASSERT_EQ(rows.size(), 6u);
  const fs::path camera = write_file("sim_camera.yaml",
                                     "camera:\n  fx: 1000.0\n  fy: 1000.0\n  cx: 640.0\n"
                                     "  cy: 512.0\n  distortion: [0, 0, 0, 0, 0]\n"
                                     "  pixel_format: mono12\n  width: 1280\n  height: 1024\n");
  nav::core::CameraRelativePoseModel model;
  model.x_body_camera << 1.0, 0.0, 0.5, 0.0, 0.0, M_PI / 2.0;
  int registered = 0;
  for (std::size_t a = 0; a + 1 < rows.size(); ++a) {
    const nav::core::Vec6 x_i_j = model.camera_relative_pose(rows[a].pose, rows[a + 1].pose);
    std::ostringstream prior;
    prior << "{\"x_i_j\": [";
    for (int k = 0; k < 6; ++k) prior << x_i_j[k] << (k < 5 ? ", " : "");
    prior << "], \"covariance\": [";
    for (int k = 0; k < 36; ++k) {
      prior << (k % 7 != 0 ? 0.0 : (k < 21 ? 0.1 * 0.1 : 0.01 * 0.01)) << (k < 35 ? ", " : "");
    }
    prior << "], \"scene_depth_m\": " << rows[a].altitude_m - 0.5
          << ", \"scene_depth_sigma_m\": 0.5}";
    char name_i[32], name_j[32];
    std::snprintf(name_i, sizeof name_i, "%06d.png", rows[a].frame);
    std::snprintf(name_j, sizeof name_j, "%06d.png", rows[a + 1].frame);
    const RunResult r = run_navtool(quoted(dive / "images" / name_i) + " " +
                                    quoted(dive / "images" / name_j) + " --camera " +
                                    quoted(camera) + " --json --prior " +
                                    quoted(write_file("sim_prior.json", prior.str())));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const json j = json::parse(r.out);
    const auto features = j.at("features").get<std::vector<double>>();
    std::printf("frames %d-%d: %s %s inliers %d putative %d comparisons %.0f of %.0f, chi2 %.2f\n",
                rows[a].frame, rows[a + 1].frame, j.at("success").get<bool>() ? "registered" : "failed:",
                j.at("reason").get<std::string>().c_str(), j.at("inliers").get<int>(),
                j.at("putative_matches").get<int>(), j.at("descriptor_comparisons").get<double>(),
                features[0] * features[1], j.at("prior_chi2").get<double>());
    EXPECT_LT(j.at("descriptor_comparisons").get<double>(), 0.5 * features[0] * features[1]);
    if (!j.at("success").get<bool>()) continue;
    ++registered;
    const auto z = j.at("measurement").get<std::vector<double>>();
    const Eigen::Matrix3d R_measured = nav::core::rotation_from_euler({z[2], z[3], z[4]});
    const Eigen::Matrix3d R_true = nav::core::rotation_from_euler(x_i_j.tail<3>());
    EXPECT_LT(Eigen::AngleAxisd(R_measured.transpose() * R_true).angle() * 180.0 / M_PI, 1.0)
        << "frames " << rows[a].frame << "-" << rows[a + 1].frame;
  }
  EXPECT_GE(registered, 3);
}

}  // namespace
