// The dive's frames into navd (hil-tests/README.md "Playing a dive back", camera): a 3-image
// simulated dive with rendered frames (19 s) played at real time by DivePlayer in the test's
// own user + network namespace (ptys and Aravis' fake GigE camera on lo), the real navd in live
// mode on the generated config. Asserted from navd's NAV_IMAGE (udpm ttl=0) and the frames navd
// wrote to the config's image_dir: one image per NAV_IMAGE of the dive, each image's time of
// validity (mapped back to dive time with the player's dive_start_us / host_start_us) at or
// after the dive's and within 100 ms beyond what the fake's own send lateness explains, and
// each written frame's pixels equal to the dive's PNG. Skipped with the reason where the
// namespace or udpm loopback is not available.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/image_metadata_t.hpp>
#include <opencv2/imgcodecs.hpp>
#include <thread>
#include <variant>

#include "../../daemon/tests/support/navd_process.h"
#include "../../daemon/tests/support/net_namespace.h"
#include "../../daemon/tests/support/udpm_probe.h"
#include "nav/hil/dive_player.h"
#include "support/background_play.h"
#include "support/sim_dive.h"

namespace {

namespace fs = std::filesystem;
using nav::sim::test::file_text;
constexpr const char* kUdpmUrl = "udpm://239.255.76.67:7683?ttl=0";
const auto* const kCleanup =
    ::testing::AddGlobalTestEnvironment(new nav::sim::test::ScratchCleanup);

struct Images {
  std::vector<navlcm::image_metadata_t> got;
  void on_image(const lcm::ReceiveBuffer*, const std::string&, const navlcm::image_metadata_t* m) {
    got.push_back(*m);
  }
};

TEST(HilCameraNavd, NavdGetsTheDivesFramesAtTheDivesImageTimes) {
  const nav::tool::test::NetNamespace& net =
      nav::tool::test::isolated_network();  // before any thread
  const std::string netns_error = net.ok ? "" : net.reason;
  if (!netns_error.empty()) GTEST_SKIP() << "no private network namespace: " << netns_error;
  const fs::path dir = nav::sim::test::scratch_dir("hil_camera_navd");
  nav::sim::SimOptions so = nav::sim::test::sim_options((dir / "dive"), 3, 3);
  so.render_images = true;
  nav::sim::simulate_dive(so, nav::sim::test::sim_config_path().string());
  std::vector<navlcm::image_metadata_t> dive;
  for (const auto& e : nav::sim::test::read_log(dir / "dive")) {
    if (const auto* m = std::get_if<navlcm::image_metadata_t>(&e)) dive.push_back(*m);
  }
  ASSERT_EQ(dive.size(), 3u);

  lcm::LCM lcm(kUdpmUrl);
  if (!lcm.good() || !nav::tool::test::udpm_loops_back(lcm, "HIL_CAMERA_PROBE"))
    GTEST_SKIP() << "udpm ttl=0 does not loop back in the namespace";
  Images images;
  lcm.subscribe("NAV_IMAGE", &Images::on_image, &images);

  nav::hil::PlayerOptions po;
  po.serial_dir = dir / "tty";
  po.reader_timeout = std::chrono::seconds(20);
  nav::hil::DivePlayer player(dir / "dive", po);
  for (const nav::hil::PlayedSensor& s : player.sensors()) {
    if (s.type == "camera_gige" && s.output != nav::hil::SensorOutput::kGige)
      GTEST_SKIP() << "fake GigE camera not played: " << s.note;
  }
  player.write_navd_config(dir / "navd.yaml", kUdpmUrl);
  const pid_t navd = nav::tool::test::spawn_navd({"--config", (dir / "navd.yaml").string()}, dir);
  ASSERT_GT(navd, 0);
  nav::hil::test::BackgroundPlay play(player);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(50);
  while (!play.done() && std::chrono::steady_clock::now() < give_up) lcm.handleTimeout(20);
  const nav::hil::PlayReport report = play.finish();
  for (int i = 0; i < 10; ++i) lcm.handleTimeout(20);
  ASSERT_EQ(::kill(navd, SIGTERM), 0);
  EXPECT_EQ(nav::tool::test::wait_exit(navd, std::chrono::seconds(5)), 0)
      << file_text(dir / "navd.stderr");

  ASSERT_TRUE(report.started) << "navd did not open the ptys: " << file_text(dir / "navd.stderr");
  EXPECT_EQ(report.camera.images, 3);
  EXPECT_EQ(report.camera.with_frame, 3);
  ASSERT_EQ(images.got.size(), dive.size()) << file_text(dir / "navd.stderr");
  double max_offset_ms = -1e9, sum_offset_ms = 0.0;
  for (std::size_t k = 0; k < dive.size(); ++k) {
    const navlcm::image_metadata_t& m = images.got[k];
    // navd's validity on the host clock, back to the dive's (speed 1).
    const double dive_t_us =
        static_cast<double>(m.time_of_validity_us - report.host_start_us + report.dive_start_us);
    const double offset_ms = (dive_t_us - static_cast<double>(dive[k].time_of_validity_us)) * 1e-3;
    max_offset_ms = std::max(max_offset_ms, offset_ms);
    sum_offset_ms += offset_ms;
    EXPECT_GE(offset_ms, -1.0) << "image " << k << ": before the dive's image time";
    EXPECT_LT(offset_ms, 100.0 + report.camera.max_send_late_s * 1e3) << "image " << k;
    ASSERT_FALSE(m.file_path.empty()) << "navd wrote no frame (camera.image_dir)";
    const cv::Mat written =
        cv::imread((po.serial_dir / m.file_path).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat expected =
        cv::imread((dir / "dive" / dive[k].file_path).string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(written.empty()) << po.serial_dir / m.file_path;
    ASSERT_EQ(written.size(), expected.size());
    EXPECT_EQ(cv::norm(written, expected, cv::NORM_INF), 0.0) << "image " << k;
    EXPECT_EQ(m.width, expected.cols);
    EXPECT_EQ(m.bits_per_pixel, 16);
  }
  std::printf(
      "navd took %zu of %zu dive images; validity - dive image time max %.2f ms, mean %.2f ms "
      "(fake send max %.2f ms after due); frames equal to the dive's PNGs; serial writes worst "
      "%.1f ms late\n",
      images.got.size(), dive.size(), max_offset_ms,
      sum_offset_ms / static_cast<double>(dive.size()), report.camera.max_send_late_s * 1e3,
      report.max_late_s * 1e3);
}

}  // namespace
