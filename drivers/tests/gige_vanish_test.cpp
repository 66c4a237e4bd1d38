// A GigE Vision camera that vanishes mid-stream (power or cable lost): GigeCamera::grab()
// reports kDisconnected instead of timing out forever, first through its own GVCP probe
// (gvcp_probe.h, about a second), and with the probe off through Aravis' heartbeat ("control
// lost", about 6 s); closing afterwards neither hangs nor crashes, and reopening after the
// camera comes back resumes the stream. Uses Aravis' fake on loopback and takes about 20 s
// (Aravis' fixed heartbeat retry schedule), hence its own executable.

#include <arpa/inet.h>
#include <arv.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <string>

#include "../src/transports/gvcp_probe.h"
#include "fake_camera_pattern.h"
#include "nav/drivers/transports/gige_camera.h"

namespace nav::drivers {
namespace {

using namespace std::chrono_literals;

sockaddr_in loopback(std::uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  return a;
}

ArvGvFakeCamera* start_fake(const char* serial) {
  ArvGvFakeCamera* gv = arv_gv_fake_camera_new("lo", serial);
  if (gv != nullptr && !arv_gv_fake_camera_is_running(gv)) g_clear_object(&gv);
  return gv;
}

/// Opens the fake at 127.0.0.1, grabs one frame, destroys the fake, and grabs until the
/// camera is reported; returns that status and the seconds from the loss to it.
std::pair<IoStatus, double> vanish(GigeCamera& camera, ArvGvFakeCamera* gv) {
  const IoStatus opened = camera.open();
  const IoStatus started = opened.ok() ? camera.start() : opened;
  CameraFrame frame;
  const IoStatus first = started.ok() ? camera.grab(frame, 2s) : started;
  g_object_unref(gv);  // power lost: no more GVSP packets, no answers on GVCP
  if (!first.ok()) return {first, 0.0};
  const auto lost = std::chrono::steady_clock::now();
  IoStatus s;
  do {
    s = camera.grab(frame, 200ms);
  } while ((s.ok() || s.code() == IoCode::kTimeout) &&
           std::chrono::steady_clock::now() < lost + 25s);
  return {s, std::chrono::duration<double>(std::chrono::steady_clock::now() - lost).count()};
}

GigeOptions fake_options(int probe_period_ms) {
  GigeOptions o;
  o.camera_id = "127.0.0.1";
  o.pixel_format = PixelFormat::kMono8;
  o.frame_rate_hz = 100.0;
  o.liveness_probe_period_ms = probe_period_ms;
  return o;
}

TEST(GvcpProbe, AFakeCameraAnswersAPortWithoutADeviceDoesNot) {
  nav::testing::LoopbackCameraLock lock;
  ArvGvFakeCamera* gv = start_fake("NAVPROBE");
  if (gv == nullptr) GTEST_SKIP() << "the Aravis GigE fake camera cannot listen on interface lo";
  GvcpProbe live(loopback(3956), 200ms, 3);
  std::string why;
  EXPECT_TRUE(live.answers(&why)) << why;
  g_object_unref(gv);
  EXPECT_FALSE(live.answers(&why));
  EXPECT_EQ(why, "no READREG_ACK from 127.0.0.1:3956 in 3 x 200 ms");
  // A port where nothing listens.
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in bound = loopback(0);
  socklen_t len = sizeof bound;
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&bound), sizeof bound), 0);
  ASSERT_EQ(::getsockname(fd, reinterpret_cast<sockaddr*>(&bound), &len), 0);
  ::close(fd);
  EXPECT_FALSE(GvcpProbe(bound, 50ms, 2).answers(&why));
  EXPECT_NE(why.find("in 2 x 50 ms"), std::string::npos) << why;
}

TEST(GigeCameraVanish, TheProbeReportsAVanishedCameraBeforeTheHeartbeat) {
  nav::testing::LoopbackCameraLock lock;
  ArvGvFakeCamera* gv = start_fake("NAVVANISH");
  if (gv == nullptr) GTEST_SKIP() << "the Aravis GigE fake camera cannot listen on interface lo";
  GigeCamera camera(fake_options(500));
  const auto [s, after_s] = vanish(camera, gv);
  EXPECT_EQ(s.code(), IoCode::kDisconnected) << s.message();
  // The probe's message, not the heartbeat's: the probe answered first (the heartbeat needs
  // about 6 s; this one at most period + tries x timeout = 1.5 s).
  EXPECT_NE(s.message().find("camera does not answer: no READREG_ACK from 127.0.0.1:3956"),
            std::string::npos)
      << s.message();
  std::printf("probe: reported %.2f s after the camera vanished\n", after_s);
  camera.close();
}

TEST(GigeCameraVanish, WithoutTheProbeTheHeartbeatReportsItThenTheCameraReopens) {
  nav::testing::LoopbackCameraLock lock;
  ArvGvFakeCamera* gv = start_fake("NAVVANISH");
  if (gv == nullptr) GTEST_SKIP() << "the Aravis GigE fake camera cannot listen on interface lo";
  auto camera = std::make_unique<GigeCamera>(fake_options(0));
  const auto [s, after_s] = vanish(*camera, gv);
  EXPECT_EQ(s.code(), IoCode::kDisconnected) << s.message();
  EXPECT_NE(s.message().find("control lost"), std::string::npos) << s.message();
  std::printf("heartbeat: reported %.2f s after the camera vanished\n", after_s);
  camera->close();  // must not hang or crash with the device gone
  EXPECT_FALSE(camera->start().ok());

  // Power back: the driver reopens the same id and frames resume.
  gv = start_fake("NAVVANISH");
  ASSERT_TRUE(gv != nullptr);
  CameraFrame frame;
  const IoStatus reopened = camera->open();
  const IoStatus restarted = reopened.ok() ? camera->start() : reopened;
  const IoStatus resumed = restarted.ok() ? camera->grab(frame, 2s) : restarted;
  camera->close();
  g_object_unref(gv);
  EXPECT_TRUE(resumed.ok()) << resumed.message();
}

}  // namespace
}  // namespace nav::drivers
