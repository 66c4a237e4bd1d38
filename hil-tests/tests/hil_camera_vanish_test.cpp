// The player's kCameraVanish fault (player_faults.h, camera_playback.h) against navd's GigE
// driver (nav::drivers::GigeCamera, as navd's camera thread uses it): a short simulated dive at
// 4 x with the fake GigE camera destroyed for the middle of the dive. Asserted: the driver's
// grab reports the camera gone (kDisconnected, from its GVCP probe or Aravis' heartbeat) after the
// vanish and not before; a new driver opens the camera again once the player has restarted it;
// every frame the player sent reaches the driver, and sent + vanished = the log's images, with
// at least one image due while the camera was gone. The detection delay is printed.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <thread>
#include <variant>

#include "../../daemon/tests/support/net_namespace.h"
#include "nav/daemon/system/host_clock.h"
#include "nav/drivers/transports/gige_camera.h"
#include "nav/hil/dive_player.h"
#include "support/background_play.h"
#include "support/sim_dive.h"

namespace {

namespace fs = std::filesystem;
const auto* const kCleanup =
    ::testing::AddGlobalTestEnvironment(new nav::sim::test::ScratchCleanup);
using nav::drivers::GigeCamera;
using nav::drivers::IoCode;

constexpr double kSpeed = 4.0;
constexpr double kVanishFromS = 12.0, kVanishToS = 40.0;  // dive seconds

std::unique_ptr<GigeCamera> open_camera() {
  nav::drivers::GigeOptions go;  // what navd opens from the generated config
  go.camera_id = "127.0.0.1";
  go.pixel_format = nav::drivers::PixelFormat::kMono12Packed;
  go.trigger_mode = nav::drivers::TriggerMode::kHardware;
  go.trigger_source = "Line1";
  auto camera = std::make_unique<GigeCamera>(go);
  if (!camera->open().ok() || !camera->start().ok()) return nullptr;
  return camera;
}

TEST(HilCameraVanish, TheDriverSeesTheCameraGoAndOpensItAgainWhenItReturns) {
  const nav::tool::test::NetNamespace& net = nav::tool::test::isolated_network();
  if (!net.ok) GTEST_SKIP() << "no private network namespace: " << net.reason;
  const fs::path dir = nav::sim::test::scratch_dir("vanish");
  nav::sim::simulate_dive(nav::sim::test::sim_options(dir / "dive", 5, 7),
                          nav::sim::test::sim_config_path().string());
  std::int64_t images = 0;
  for (const auto& e : nav::sim::test::read_log(dir / "dive"))
    images += std::holds_alternative<navlcm::image_metadata_t>(e) ? 1 : 0;

  nav::hil::PlayerOptions po;
  po.serial_dir = dir / "tty";
  po.wait_for_readers = false;  // the camera alone
  po.speed = kSpeed;
  po.faults.push_back({nav::hil::FaultKind::kCameraVanish, "camera", kVanishFromS, kVanishToS, 0});
  std::atomic<std::int64_t> host_start_us{0};
  po.on_start = [&](std::int64_t, std::int64_t host_us) { host_start_us.store(host_us); };
  nav::hil::DivePlayer player(dir / "dive", po);
  std::unique_ptr<GigeCamera> camera = open_camera();
  if (!camera) GTEST_SKIP() << "the fake GigE camera is not served here";

  nav::hil::test::BackgroundPlay play(player);
  std::int64_t frames = 0, lost_at_us = 0, reopened_at_us = 0;
  nav::drivers::CameraFrame frame;
  const std::int64_t give_up_us = nav::daemon::monotonic_us() + 60'000'000;
  while (!play.done() && nav::daemon::monotonic_us() < give_up_us) {
    if (!camera) {  // navd's camera thread: open again after a backoff
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      if ((camera = open_camera())) reopened_at_us = nav::daemon::monotonic_us();
      continue;
    }
    const nav::drivers::IoStatus s = camera->grab(frame, std::chrono::milliseconds(200));
    if (s.ok()) ++frames;
    if (!s.ok() && s.code() != IoCode::kTimeout) {
      EXPECT_EQ(s.code(), IoCode::kDisconnected) << s.message();
      if (lost_at_us == 0) lost_at_us = nav::daemon::monotonic_us();
      camera->stop();
      camera.reset();
    }
  }
  for (int i = 0; camera && i < 5; ++i) frames += camera->grab(frame, std::chrono::seconds(1)).ok();
  const nav::hil::PlayReport report = play.finish();

  const double vanish_us = host_start_us.load() + kVanishFromS * 1e6 / kSpeed;
  const double back_us = host_start_us.load() + kVanishToS * 1e6 / kSpeed;
  ASSERT_GT(lost_at_us, 0) << "the driver never saw the camera go";
  EXPECT_GE(lost_at_us, vanish_us) << "control lost before the camera vanished";
  ASSERT_GT(reopened_at_us, 0) << "the driver never opened the camera again";
  EXPECT_GE(reopened_at_us, back_us) << "opened while the camera was gone";
  EXPECT_TRUE(report.camera.reappear_error.empty()) << report.camera.reappear_error;
  EXPECT_EQ(report.camera.vanishes, 1);
  EXPECT_GE(report.camera.vanished, 1);
  EXPECT_EQ(report.camera.images, images);
  EXPECT_EQ(report.camera.sent + report.camera.vanished, images);
  EXPECT_EQ(frames, report.camera.sent) << "frames received vs sent";
  std::printf(
      "camera gone %.2f s after it vanished, opened again %.2f s after it returned; "
      "%lld of %lld images sent, %lld due while gone\n",
      (lost_at_us - vanish_us) * 1e-6, (reopened_at_us - back_us) * 1e-6,
      static_cast<long long>(report.camera.sent), static_cast<long long>(images),
      static_cast<long long>(report.camera.vanished));
}

}  // namespace
