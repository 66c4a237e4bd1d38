// The player's camera alone (hil-tests/README.md "Playing a dive back", camera): a short
// simulated dive played by DivePlayer with Aravis' fake GigE camera on this process' own lo
// (user + network namespace), received by navd's GigE driver (nav::drivers::GigeCamera,
// Mono12Packed, hardware trigger on Line1 as the generated navd config sets it). Asserted: one
// frame per NAV_IMAGE of the log, each frame's pixels equal to the dive's rendered PNG (or the
// documented test pattern when the dive has none), and no frame reaching the host before the
// vehicle's did (dive validity + camera latency, mapped to host time). The offsets are printed.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <thread>
#include <variant>

#include "../../daemon/tests/support/navd_process.h"
#include "../../daemon/tests/support/net_namespace.h"
#include "nav/daemon/config/config.h"
#include "nav/drivers/transports/gige_camera.h"
#include "nav/hil/dive_player.h"
#include "support/sim_dive.h"

namespace {

namespace fs = std::filesystem;
const auto* const kCleanup =
    ::testing::AddGlobalTestEnvironment(new nav::sim::test::ScratchCleanup);
using nav::drivers::CameraFrame;
using nav::drivers::GigeCamera;
using nav::drivers::GigeOptions;

struct DiveImage {
  std::int64_t validity_us = 0;
  std::string file_path;
};

std::vector<DiveImage> dive_images(const fs::path& dive) {
  std::vector<DiveImage> images;
  for (const auto& e : nav::sim::test::read_log(dive)) {
    if (const auto* m = std::get_if<navlcm::image_metadata_t>(&e))
      images.push_back({m->time_of_validity_us, m->file_path});
  }
  return images;
}

double camera_latency_s(const fs::path& dive) {
  const auto config = nav::daemon::load_config_file((dive / "config.yaml").string());
  for (const auto& s : config.sensors)
    if (s.type == nav::daemon::SensorType::kCameraGige) return s.latency_s;
  return 0.0;
}

/// The fake's test pattern (fake_gige_camera.h): pixel (x, y) of the n-th pattern frame.
cv::Mat test_pattern(int width, int height, std::int64_t n) {
  cv::Mat m(height, width, CV_16UC1);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      m.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>((x * 7 + y * 13 + n * 101) & 0xfff);
  return m;
}

struct Received {
  cv::Mat image;
  std::int64_t arrival_monotonic_us = 0;  ///< as navd dates it (camera_source.cpp)
};

/// Simulates `images` images (rendered or not), plays them at `speed` and grabs the frames.
void play_and_check(bool render, double speed) {
  const nav::tool::test::NetNamespace& net =
      nav::tool::test::isolated_network();  // before any thread
  const std::string netns_error = net.ok ? "" : net.reason;
  if (!netns_error.empty()) GTEST_SKIP() << "no private network namespace: " << netns_error;
  const fs::path dir = nav::sim::test::scratch_dir(render ? "frames" : "pattern");
  nav::sim::SimOptions so = nav::sim::test::sim_options((dir / "dive"), 5, 3);
  so.render_images = render;
  nav::sim::simulate_dive(so, nav::sim::test::sim_config_path().string());
  const std::vector<DiveImage> images = dive_images(dir / "dive");
  ASSERT_EQ(images.size(), 3u);

  nav::hil::PlayerOptions po;
  po.serial_dir = dir / "tty";
  po.wait_for_readers = false;  // no serial reader here: the camera alone
  po.speed = speed;
  std::atomic<std::int64_t> dive_start_us{0}, host_start_us{0};
  po.on_start = [&](std::int64_t dive_us, std::int64_t host_us) {
    dive_start_us.store(dive_us);
    host_start_us.store(host_us);
  };
  nav::hil::DivePlayer player(dir / "dive", po);
  const auto camera_plan =
      std::find_if(player.sensors().begin(), player.sensors().end(),
                   [](const nav::hil::PlayedSensor& s) { return s.type == "camera_gige"; });
  ASSERT_NE(camera_plan, player.sensors().end());
  if (camera_plan->output != nav::hil::SensorOutput::kGige)
    GTEST_SKIP() << "fake GigE camera not played: " << camera_plan->note;

  // The generated navd config: the player triggers the camera (Line1), navd writes its frames.
  player.write_navd_config(dir / "navd.yaml", "memq://");
  const auto navd_config = nav::daemon::load_config_file((dir / "navd.yaml").string());
  const auto navd_camera = std::find_if(
      navd_config.sensors.begin(), navd_config.sensors.end(),
      [](const nav::daemon::SensorConfig& s) { return nav::daemon::is_camera(s.type); });
  ASSERT_NE(navd_camera, navd_config.sensors.end());
  EXPECT_EQ(navd_camera->camera.trigger, nav::daemon::Trigger::kHardware);
  EXPECT_EQ(navd_camera->camera.pixel_format, nav::daemon::PixelFormat::kMono12);
  EXPECT_EQ(navd_camera->camera.image_dir, (po.serial_dir / "images").string());

  GigeOptions go;  // what navd opens from the generated config
  go.camera_id = "127.0.0.1";
  go.pixel_format = nav::drivers::PixelFormat::kMono12Packed;
  go.trigger_mode = nav::drivers::TriggerMode::kHardware;
  go.trigger_source = "Line1";
  GigeCamera camera(go);
  const nav::drivers::IoStatus opened = camera.open();
  ASSERT_TRUE(opened.ok()) << opened.message();
  ASSERT_EQ(camera.width(), 1280);  // 2 cx x 2 cy of config/sim.yaml: the rendered frame
  ASSERT_EQ(camera.height(), 1024);
  ASSERT_TRUE(camera.start().ok());

  std::atomic<bool> stop{false};
  nav::hil::PlayReport report;
  std::thread play([&] { report = player.play(stop); });
  std::vector<Received> got;
  CameraFrame frame;
  for (std::size_t i = 0; i < images.size() + 1; ++i) {
    // One more grab than images: no extra frame may come (it times out after the dive).
    const nav::drivers::IoStatus s = camera.grab(frame, std::chrono::seconds(i == 0 ? 8 : 5));
    if (!s.ok()) break;
    const std::int64_t arrival_mono =
        frame.arrival_realtime_us ? *frame.arrival_realtime_us -
                                        (frame.time.host.realtime_us - frame.time.host.monotonic_us)
                                  : frame.time.host.monotonic_us;
    got.push_back({frame.image.clone(), std::min(arrival_mono, frame.time.host.monotonic_us)});
  }
  play.join();
  camera.stop();

  ASSERT_EQ(got.size(), images.size()) << "frames received vs NAV_IMAGE events in the log";
  EXPECT_EQ(report.camera.images, static_cast<std::int64_t>(images.size()));
  EXPECT_EQ(report.camera.sent, static_cast<std::int64_t>(images.size()));
  EXPECT_EQ(report.camera.with_frame, render ? report.camera.images : 0);
  EXPECT_EQ(report.camera.not_taken, 0);
  EXPECT_EQ(report.images_not_played, 0);
  const double latency_us = camera_latency_s(dir / "dive") * 1e6;
  double max_offset_ms = -1e9, sum_offset_ms = 0.0;
  for (std::size_t k = 0; k < images.size(); ++k) {
    const cv::Mat expected =
        render ? cv::imread((dir / "dive" / images[k].file_path).string(), cv::IMREAD_UNCHANGED)
               : test_pattern(1280, 1024, static_cast<std::int64_t>(k));
    ASSERT_EQ(expected.type(), CV_16UC1) << images[k].file_path;
    ASSERT_EQ(got[k].image.size(), expected.size());
    EXPECT_EQ(cv::norm(got[k].image, expected, cv::NORM_INF), 0.0) << "frame " << k;
    const double due_us =
        host_start_us.load() +
        (images[k].validity_us + latency_us - static_cast<double>(dive_start_us.load())) / speed;
    const double offset_ms = (got[k].arrival_monotonic_us - due_us) * 1e-3;
    // The fill callback holds the frame until its due time: it never reaches the host before.
    EXPECT_GE(offset_ms, -1.0) << "frame " << k;
    max_offset_ms = std::max(max_offset_ms, offset_ms);
    sum_offset_ms += offset_ms;
  }
  std::printf(
      "%zu frames (%s) at speed %g: arrival - due max %.2f ms, mean %.2f ms; fake send "
      "max %.2f ms after due\n",
      got.size(), render ? "rendered PNGs" : "test pattern", speed, max_offset_ms,
      sum_offset_ms / static_cast<double>(got.size()), report.camera.max_send_late_s * 1e3);
}

TEST(HilCamera, ServesTheDivesRenderedFramesAtItsImageTimes) { play_and_check(true, 4.0); }

TEST(HilCamera, ServesTheTestPatternAtTheImageTimesWithoutRenderedFrames) {
  play_and_check(false, 4.0);
}

}  // namespace
