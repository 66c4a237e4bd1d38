// GigeCamera against Aravis' fake as a real GigE Vision device on loopback (GVCP control and
// GVSP streaming through the kernel's UDP stack): pixels, device time stamps and the 16-bit
// block-id wrap-around, software trigger, and packet loss (arv-fake-gv-camera-0.8 -r) counted
// as incomplete buffers. Skips with the reason when the fake cannot listen on lo.

#include <arv.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "fake_camera_pattern.h"
#include "nav/drivers/transports/gige_camera.h"
#include "nav/testing/child_process.h"

namespace nav::drivers {
namespace {

using namespace std::chrono_literals;
using nav::testing::expect_pattern_stream;
using nav::testing::fill_test_pattern;

GigeOptions fake_options(PixelFormat format) {
  GigeOptions o;
  o.pixel_format = format;
  o.exposure_us = 1000.0;
  o.gain = 2.0;
  o.frame_rate_hz = 500.0;  // 135 frames from the fake's first block id (65400) to the wrap
  o.buffer_count = 16;
  return o;
}

// ---- GigE Vision on loopback: the fake as a network camera (GVCP control, GVSP stream). ----

class GigeCameraLoopback : public ::testing::Test {
 protected:
  void SetUp() override {
    serial_ = "NAV" + std::to_string(::getpid() % 100000);
    gv_ = arv_gv_fake_camera_new("lo", serial_.c_str());
    if (gv_ == nullptr || !arv_gv_fake_camera_is_running(gv_)) {
      GTEST_SKIP() << "the Aravis GigE fake camera cannot listen on interface lo here";
    }
    arv_fake_camera_set_fill_pattern(arv_gv_fake_camera_get_fake_camera(gv_), fill_test_pattern,
                                     &capacity_);
  }
  /// Opens camera_ and sizes the pattern for the payload of the chosen pixel format.
  IoStatus open(const GigeOptions& o) {
    camera_ = std::make_unique<GigeCamera>(o);
    IoStatus s = camera_->open();
    capacity_ = arv_fake_camera_get_payload(arv_gv_fake_camera_get_fake_camera(gv_));
    return s;
  }
  void TearDown() override {
    camera_.reset();
    if (gv_ != nullptr) g_object_unref(gv_);
  }
  GigeOptions options(PixelFormat format) const {
    GigeOptions o = fake_options(format);
    // By address: Aravis opens it through lo (a name found by broadcast discovery may be
    // answered through another interface, whose address the stream would then listen on).
    o.camera_id = "127.0.0.1";
    return o;
  }

  nav::testing::LoopbackCameraLock lock_;  // first member: taken before the fake starts
  std::string serial_;
  ArvGvFakeCamera* gv_ = nullptr;
  size_t capacity_ = 0;
  std::unique_ptr<GigeCamera> camera_;
};

TEST_F(GigeCameraLoopback, StreamsOverGvspWithDeviceTimestampsAcrossTheIdWrap) {
  const IoStatus s = open(options(PixelFormat::kMono16));
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_TRUE(camera_->start().ok());
  expect_pattern_stream(*camera_, PixelFormat::kMono16, 160, true);
}

TEST_F(GigeCameraLoopback, SoftwareTriggerGivesOneFramePerTrigger) {
  GigeOptions o = options(PixelFormat::kMono8);
  o.trigger_mode = TriggerMode::kSoftware;
  o.packet_size_bytes = 1000;  // fixed instead of negotiated
  ASSERT_TRUE(open(o).ok());
  EXPECT_EQ(arv_camera_gv_get_packet_size(camera_->native_handle(), nullptr), 1000u);
  ASSERT_TRUE(camera_->start().ok());
  CameraFrame frame;
  EXPECT_EQ(camera_->grab(frame, 300ms).code(), IoCode::kTimeout);  // free-run would give ~150
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(camera_->trigger().ok());
    const IoStatus s = camera_->grab(frame, 2s);
    ASSERT_TRUE(s.ok()) << s.message();
  }
  EXPECT_EQ(camera_->grab(frame, 100ms).code(), IoCode::kTimeout);
  EXPECT_EQ(camera_->stats().frames, 3u);
}

/// Runs arv-fake-gv-camera-0.8 as a separate process (killed by pid in the destructor).
class FakeGvProcess {
 public:
  FakeGvProcess(const std::string& serial, int lost_per_thousand) {
    const std::string ratio = std::to_string(lost_per_thousand);  // no allocation after fork()
    pid_ = ::fork();
    if (pid_ == 0) {
      ::execl(NAV_ARV_FAKE_GV_CAMERA, NAV_ARV_FAKE_GV_CAMERA, "-i", "127.0.0.1", "-s",
              serial.c_str(), "-r", ratio.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
  }
  ~FakeGvProcess() { (void)nav::testing::terminate_child(pid_); }
  bool started() const { return pid_ > 0; }
  bool exited() {
    if (pid_ <= 0 || ::waitpid(pid_, nullptr, WNOHANG) != pid_) return false;
    pid_ = -1;
    return true;
  }

 private:
  pid_t pid_ = -1;
};

TEST(GigeCameraLoss, DroppedPacketsAreCountedAsIncompleteBuffers) {
  if (!std::filesystem::exists(NAV_ARV_FAKE_GV_CAMERA)) {
    GTEST_SKIP() << "arv-fake-gv-camera-0.8 not found at configure time (" NAV_ARV_FAKE_GV_CAMERA
                    ")";
  }
  const std::string serial = "NAVLOSS" + std::to_string(::getpid() % 100000);
  nav::testing::LoopbackCameraLock lock;
  FakeGvProcess fake(serial, 20);  // 2 % of GVSP packets lost, resends never answered
  ASSERT_TRUE(fake.started());
  std::this_thread::sleep_for(300ms);
  if (fake.exited())
    GTEST_SKIP() << "arv-fake-gv-camera-0.8 exited at once (GVCP port 3956 on lo busy?)";
  GigeOptions o = fake_options(PixelFormat::kMono16);
  o.camera_id = "127.0.0.1";
  o.frame_rate_hz = 100.0;
  GigeCamera camera(o);
  IoStatus s;
  for (int attempt = 0; attempt < 20; ++attempt) {  // the process needs a moment to listen
    if ((s = camera.open()).ok()) break;
    std::this_thread::sleep_for(100ms);
  }
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_TRUE(camera.start().ok());
  CameraFrame frame;
  const auto deadline = std::chrono::steady_clock::now() + 3s;
  while (camera.stats().incomplete < 3 && std::chrono::steady_clock::now() < deadline) {
    s = camera.grab(frame, 500ms);
    ASSERT_TRUE(s.ok() || s.code() == IoCode::kTimeout) << s.message();
  }
  EXPECT_GE(camera.stats().incomplete, 3u) << "frames " << camera.stats().frames;
  camera.close();
}

}  // namespace
}  // namespace nav::drivers
