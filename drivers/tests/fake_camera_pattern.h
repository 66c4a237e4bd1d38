#pragma once
// Test support for camera transports (drivers tests only): a known image pattern that Aravis'
// fake cameras serve through arv_fake_camera_set_fill_pattern, and a checker that grabs frames
// and verifies pixels, frame ids (with gaps) and time stamps.

#include <arv.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <opencv2/core.hpp>
#include <vector>

#include "nav/drivers/transports/gige_camera.h"
#include "nav/drivers/transports/mono_unpack.h"

namespace nav::testing {

using nav::drivers::CameraFrame;
using nav::drivers::GigeCamera;
using nav::drivers::ImageLayout;
using nav::drivers::IoStatus;
using nav::drivers::pack_mono;
using nav::drivers::pixel_format_from_pfnc;
using nav::drivers::PixelFormat;
using nav::drivers::significant_bits;
using nav::drivers::unpacked_cv_type;

/// Pixel (x, y) of the test pattern, `bits` wide.
inline uint16_t pattern_value(int x, int y, int bits) {
  return static_cast<uint16_t>((x * 37 + y * 101 + 5) & ((1 << bits) - 1));
}

inline cv::Mat pattern_image(int width, int height, PixelFormat format) {
  cv::Mat m(height, width, unpacked_cv_type(format));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const uint16_t v = pattern_value(x, y, significant_bits(format));
      if (format == PixelFormat::kMono8)
        m.at<uint8_t>(y, x) = static_cast<uint8_t>(v);
      else
        m.at<uint16_t>(y, x) = v;
    }
  }
  return m;
}

/// Fill-pattern callback (runs on the fake's thread): writes the test pattern in the buffer's
/// own format and layout. `capacity` points at the payload size the buffers were allocated with
/// (the fake reports no received size before filling).
inline void fill_test_pattern(ArvBuffer* buffer, void* capacity, guint32, guint32,
                              ArvPixelFormat pixel_format) {
  const auto format = pixel_format_from_pfnc(pixel_format);
  if (!format) return;
  const ImageLayout layout{arv_buffer_get_image_width(buffer), arv_buffer_get_image_height(buffer),
                           *format, 0};
  const std::vector<uint8_t> bytes =
      pack_mono(pattern_image(layout.width, layout.height, *format), layout);
  size_t ignored = 0;
  auto* data = static_cast<uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, &ignored)));
  std::memcpy(data, bytes.data(), std::min(*static_cast<const size_t*>(capacity), bytes.size()));
}

/// Serves the test pattern from the in-process fake behind `camera` (after open()).
inline void serve_pattern(const GigeCamera& camera, size_t& capacity) {
  capacity = arv_camera_get_payload(camera.native_handle(), nullptr);
  ArvFakeCamera* fake = arv_fake_device_get_fake_camera(
      ARV_FAKE_DEVICE(arv_camera_get_device(camera.native_handle())));
  arv_fake_camera_set_fill_pattern(fake, fill_test_pattern, &capacity);
}

/// Grabs `n` frames and checks ids, timestamps and pixels against the pattern.
inline void expect_pattern_stream(GigeCamera& camera, PixelFormat format, int n, bool expect_wrap) {
  CameraFrame frame;
  uint64_t previous_id = 0, lost = 0;
  int64_t previous_sensor_us = 0;
  bool wrapped = false;
  const cv::Mat expected = pattern_image(camera.width(), camera.height(), format);
  for (int i = 0; i < n; ++i) {
    const IoStatus s = camera.grab(frame, std::chrono::seconds(2));
    ASSERT_TRUE(s.ok()) << s.message() << " incomplete " << camera.stats().incomplete
                        << " unpack errors " << camera.stats().unpack_errors << " underruns "
                        << camera.stats().underruns;
    ASSERT_EQ(frame.format, format);
    ASSERT_TRUE(frame.time.sensor_time_us.has_value());
    ASSERT_TRUE(frame.arrival_realtime_us.has_value());
    EXPECT_GT(frame.time.host.monotonic_us, 0);
    if (i > 0) {
      ASSERT_EQ(frame.frame_id, previous_id + 1 + frame.lost_before);
      ASSERT_GT(*frame.time.sensor_time_us, previous_sensor_us);
      wrapped = wrapped || frame.raw_frame_id < 100;
    }
    lost += frame.lost_before;
    previous_id = frame.frame_id;
    previous_sensor_us = *frame.time.sensor_time_us;
    if (i == 0 || i == n - 1) {
      ASSERT_EQ(frame.image.size(), expected.size());
      EXPECT_EQ(cv::norm(frame.image, expected, cv::NORM_INF), 0.0) << "frame " << i;
    }
  }
  EXPECT_EQ(camera.stats().frames, static_cast<uint64_t>(n));
  EXPECT_EQ(camera.stats().lost, lost);
  if (expect_wrap) {
    EXPECT_TRUE(wrapped) << "block id never wrapped past 65535";
  }
}

/// Serialises tests that run a GigE fake camera on loopback: two fakes bound to 127.0.0.1:3956
/// (ctest -j) would answer each other's control packets. Held for the lifetime of the object.
class LoopbackCameraLock {
 public:
  LoopbackCameraLock()
      : fd_(::open("/tmp/navd-gige-loopback.lock", O_RDWR | O_CREAT | O_CLOEXEC, 0666)) {
    if (fd_ >= 0) (void)::flock(fd_, LOCK_EX);
  }
  ~LoopbackCameraLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  LoopbackCameraLock(const LoopbackCameraLock&) = delete;
  LoopbackCameraLock& operator=(const LoopbackCameraLock&) = delete;

 private:
  int fd_;
};

}  // namespace nav::testing
