// A GigE Vision camera that vanishes mid-stream (power or cable lost): Aravis' heartbeat
// declares "control lost" and GigeCamera::grab() reports kDisconnected instead of timing out
// forever; closing afterwards neither hangs nor crashes, and reopening after the camera comes
// back resumes the stream. Uses Aravis' fake on loopback and takes about 15 s (Aravis' fixed
// heartbeat retry schedule), hence its own executable.

#include <arv.h>
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "fake_camera_pattern.h"
#include "nav/drivers/transports/gige_camera.h"

namespace nav::drivers {
namespace {

using namespace std::chrono_literals;

TEST(GigeCameraVanish, CameraVanishingMidStreamIsReportedThenReopened) {
  nav::testing::LoopbackCameraLock lock;
  ArvGvFakeCamera* gv = arv_gv_fake_camera_new("lo", "NAVVANISH");
  if (gv == nullptr || !arv_gv_fake_camera_is_running(gv)) {
    if (gv != nullptr) g_object_unref(gv);
    GTEST_SKIP() << "the Aravis GigE fake camera cannot listen on interface lo here";
  }
  GigeOptions o;
  o.camera_id = "127.0.0.1";
  o.pixel_format = PixelFormat::kMono8;
  o.frame_rate_hz = 100.0;
  auto camera = std::make_unique<GigeCamera>(o);
  const IoStatus opened = camera->open();
  if (!opened.ok()) g_object_unref(gv);
  ASSERT_TRUE(opened.ok()) << opened.message();
  ASSERT_TRUE(camera->start().ok());
  CameraFrame frame;
  const IoStatus first = camera->grab(frame, 2s);
  g_object_unref(gv);  // power lost: no more GVSP packets, no heartbeat answers
  ASSERT_TRUE(first.ok()) << first.message();
  IoStatus s;
  const auto deadline = std::chrono::steady_clock::now() + 25s;
  do {
    s = camera->grab(frame, 200ms);
  } while ((s.ok() || s.code() == IoCode::kTimeout) && std::chrono::steady_clock::now() < deadline);
  EXPECT_EQ(s.code(), IoCode::kDisconnected) << s.message();
  EXPECT_NE(s.message().find("control lost"), std::string::npos);
  camera->close();  // must not hang or crash with the device gone
  EXPECT_FALSE(camera->start().ok());

  // Power back: the driver reopens the same id and frames resume.
  gv = arv_gv_fake_camera_new("lo", "NAVVANISH");
  ASSERT_TRUE(gv != nullptr && arv_gv_fake_camera_is_running(gv));
  const IoStatus reopened = camera->open();
  const IoStatus restarted = reopened.ok() ? camera->start() : reopened;
  const IoStatus resumed = restarted.ok() ? camera->grab(frame, 2s) : restarted;
  camera->close();
  g_object_unref(gv);
  EXPECT_TRUE(resumed.ok()) << resumed.message();
}

}  // namespace
}  // namespace nav::drivers
