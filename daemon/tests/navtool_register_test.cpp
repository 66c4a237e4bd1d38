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
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
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

// Image files carry no pixel format: without camera.pixel_format a 16-bit file is taken at its
// 16-bit full scale, and a file with alpha registers like its colour. The Sparus pair written
// as 16 bits per channel (x 257) and as BGRA gives the 8-bit pair's answer; declared mono12 the
// 16-bit file is refused as a wrong pixel depth.
TEST(NavtoolRegister, SixteenBitAndAlphaFilesRegisterLikeTheirEightBitColour) {
  NAV_REQUIRE_DATA(frame1, "images/sparus/frame_01.png");
  const fs::path frame4 = frame1.parent_path() / "frame_04.png";
  std::string camera = slurp(sparus_camera_yaml());
  camera.erase(camera.find("  pixel_format: mono8\n"));
  const fs::path no_format = write_file("sparus_no_format.yaml", camera);
  const fs::path mono12 = write_file("sparus_mono12.yaml", camera + "  pixel_format: mono12\n");
  std::vector<std::string> args16, args_alpha;
  for (const fs::path& frame : {frame1, frame4}) {
    const cv::Mat bgr = cv::imread(frame.string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(bgr.type(), CV_8UC3);
    cv::Mat bgr16, bgra;
    bgr.convertTo(bgr16, CV_16UC3, 257.0);
    cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
    const fs::path p16 = temp_dir() / ("16_" + frame.filename().string());
    const fs::path pa = temp_dir() / ("alpha_" + frame.filename().string());
    ASSERT_TRUE(cv::imwrite(p16.string(), bgr16));
    ASSERT_TRUE(cv::imwrite(pa.string(), bgra));
    args16.push_back(quoted(p16));
    args_alpha.push_back(quoted(pa));
  }
  const auto answer = [&](const std::string& pair, const fs::path& camera_yaml) {
    const RunResult r = run_navtool(pair + " --camera " + quoted(camera_yaml) + " --json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? json::parse(r.out) : json();
  };
  const json eight = answer(quoted(frame1) + " " + quoted(frame4), no_format);
  const json sixteen = answer(args16[0] + " " + args16[1], no_format);
  const json alpha = answer(args_alpha[0] + " " + args_alpha[1], no_format);
  ASSERT_TRUE(eight.at("success").get<bool>()) << eight.at("reason");
  ASSERT_TRUE(alpha.at("success").get<bool>()) << alpha.at("reason");
  ASSERT_TRUE(sixteen.at("success").get<bool>()) << sixteen.at("reason");
  // Alpha is dropped before anything else: the same answer to the bit.
  EXPECT_EQ(alpha.at("measurement"), eight.at("measurement"));
  EXPECT_EQ(alpha.at("inliers"), eight.at("inliers"));
  // 16 bits round the grey differently (a level in 255 at most), which moves features by a
  // fraction of their noise and LMedS to other samples: the answers agree within the 8-bit
  // answer's covariance (chi2_5 at 95 %; 2.3 measured).
  const auto z16 = sixteen.at("measurement").get<std::vector<double>>();
  const auto z8 = eight.at("measurement").get<std::vector<double>>();
  const auto c8 = eight.at("covariance").get<std::vector<double>>();
  Eigen::Matrix<double, 5, 1> dz;
  Eigen::Matrix<double, 5, 5> C;
  for (int r = 0; r < 5; ++r) {
    dz[r] = std::remainder(z16[r] - z8[r], 2.0 * M_PI);
    for (int c = 0; c < 5; ++c) C(r, c) = c8[5 * r + c];
  }
  const double chi2 = dz.dot(C.ldlt().solve(dz));
  std::printf("16-bit against 8-bit: inliers %d / %d, chi2 of the difference %.3f\n",
              sixteen.at("inliers").get<int>(), eight.at("inliers").get<int>(), chi2);
  EXPECT_LT(chi2, 11.07);
  EXPECT_NEAR(sixteen.at("inliers").get<double>(), eight.at("inliers").get<double>(),
              0.05 * eight.at("inliers").get<double>());
  const RunResult wrong = run_navtool(args16[0] + " " + args16[1] + " --camera " + quoted(mono12));
  EXPECT_EQ(wrong.exit_code, 1);
  EXPECT_NE(wrong.err.find("wrong pixel depth"), std::string::npos) << wrong.err;
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
