// V4L2 capture: format negotiation, layouts from bytesperline, and per-buffer bookkeeping
// (sequence gaps, error flag, short buffers, time stamps) as pure functions; then the device
// paths that work without a camera (missing node, a node that is not V4L2); the real capture
// test skips with the reason when there is no /dev/video*.

#include "nav/drivers/transports/v4l2_camera.h"

#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <filesystem>
#include <opencv2/core.hpp>

namespace nav::drivers {
namespace {

using namespace std::chrono_literals;

TEST(V4l2Format, FourccsMatchTheKernelHeaders) {
  EXPECT_EQ(kV4l2Y16, static_cast<uint32_t>(V4L2_PIX_FMT_Y16));
  EXPECT_EQ(kV4l2Y12, static_cast<uint32_t>(V4L2_PIX_FMT_Y12));
  EXPECT_EQ(kV4l2Grey, static_cast<uint32_t>(V4L2_PIX_FMT_GREY));
  EXPECT_EQ(pixel_format_from_v4l2(V4L2_PIX_FMT_Y12), PixelFormat::kMono12);
  EXPECT_FALSE(pixel_format_from_v4l2(V4L2_PIX_FMT_YUYV).has_value());
}

TEST(V4l2Format, ChoosesTheFirstPreferredFormatOffered) {
  const uint32_t offered[] = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_Y12};
  const uint32_t preferred[] = {kV4l2Y16, kV4l2Y12, kV4l2Grey};
  EXPECT_EQ(choose_v4l2_format(offered, preferred), kV4l2Y12);
  const uint32_t colour_only[] = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG};
  EXPECT_FALSE(choose_v4l2_format(colour_only, preferred).has_value());
  EXPECT_FALSE(choose_v4l2_format({}, preferred).has_value());
}

TEST(V4l2Format, LayoutTakesLinePaddingFromBytesPerLine) {
  const auto l = v4l2_layout(kV4l2Y16, 1360, 1024, 2752);  // 1360 * 2 = 2720 + 32 padding
  ASSERT_TRUE(l.has_value());
  EXPECT_EQ(l->line_padding_bytes, 32u);
  EXPECT_EQ(l->format, PixelFormat::kMono16);
  EXPECT_EQ(v4l2_layout(kV4l2Grey, 640, 480, 0)->line_padding_bytes, 0u);
  EXPECT_FALSE(v4l2_layout(kV4l2Y16, 1360, 1024, 2000).has_value());  // shorter than a line
  EXPECT_FALSE(v4l2_layout(V4L2_PIX_FMT_YUYV, 8, 8, 16).has_value());
}

TEST(V4l2Options, ValidateNamesTheBadField) {
  V4l2Options o;
  EXPECT_TRUE(o.validate().ok());
  o.buffer_count = 1;
  EXPECT_NE(o.validate().message().find("buffer_count"), std::string::npos);
  o = V4l2Options{};
  o.formats = {V4L2_PIX_FMT_YUYV};
  EXPECT_NE(o.validate().message().find("fourcc"), std::string::npos);
  o = V4l2Options{};
  o.width = 0;
  EXPECT_FALSE(o.validate().ok());
}

class V4l2Buffers : public ::testing::Test {
 protected:
  // 3x2 Y12 image with 2 padding bytes per line (bytesperline 8): words little endian.
  // line 0: 0x001 0x7FF 0xFFF, line 1: 0x123 0x456 0x789
  const std::vector<uint8_t> bytes_{0x01, 0x00, 0xFF, 0x07, 0xFF, 0x0F, 0xAA,
                                    0xAA, 0x23, 0x01, 0x56, 0x04, 0x89, 0x07};
  const ImageLayout layout_ = *v4l2_layout(kV4l2Y12, 3, 2, 8);
  FrameIdUnwrapper ids_{32, false};
  CameraStats stats_;
  CameraFrame frame_;
  V4l2BufferInfo info(uint32_t sequence) const {
    return {sequence, false, true, 5'000'000 + sequence * 33'333,
            static_cast<uint32_t>(bytes_.size())};
  }
};

TEST_F(V4l2Buffers, ConvertsPixelsSequenceAndMonotonicTimestamp) {
  ASSERT_TRUE(
      v4l2_buffer_to_frame(bytes_, info(0), layout_, HostTime{7, 8}, ids_, stats_, frame_).ok());
  ASSERT_EQ(frame_.image.type(), CV_16UC1);
  EXPECT_EQ(frame_.image.at<uint16_t>(0, 1), 0x7FF);
  EXPECT_EQ(frame_.image.at<uint16_t>(1, 2), 0x789);
  EXPECT_EQ(frame_.time.sensor_time_us, 5'000'000);
  EXPECT_EQ(frame_.time.host.monotonic_us, 7);
  EXPECT_EQ(stats_.frames, 1u);
}

TEST_F(V4l2Buffers, SequenceGapsCountLostFrames) {
  ASSERT_TRUE(v4l2_buffer_to_frame(bytes_, info(10), layout_, {}, ids_, stats_, frame_).ok());
  ASSERT_TRUE(v4l2_buffer_to_frame(bytes_, info(13), layout_, {}, ids_, stats_, frame_).ok());
  EXPECT_EQ(frame_.lost_before, 2u);
  EXPECT_EQ(stats_.lost, 2u);
  EXPECT_EQ(frame_.frame_id, 13u);
}

TEST_F(V4l2Buffers, ErrorFlaggedOrShortBuffersAreCountedAndLeaveTheFrame) {
  V4l2BufferInfo bad = info(1);
  bad.error = true;
  EXPECT_FALSE(v4l2_buffer_to_frame(bytes_, bad, layout_, {}, ids_, stats_, frame_).ok());
  V4l2BufferInfo short_buffer = info(2);
  short_buffer.bytes_used = 10;  // needs 8 + 6 = 14
  const IoStatus s = v4l2_buffer_to_frame(bytes_, short_buffer, layout_, {}, ids_, stats_, frame_);
  EXPECT_NE(s.message().find("needs 14"), std::string::npos) << s.message();
  EXPECT_EQ(stats_.incomplete, 2u);
  EXPECT_EQ(stats_.frames, 0u);
  EXPECT_TRUE(frame_.image.empty());
}

TEST_F(V4l2Buffers, RealtimeStampedDriversGiveNoSensorTime) {
  V4l2BufferInfo i = info(0);
  i.monotonic_clock = false;
  ASSERT_TRUE(v4l2_buffer_to_frame(bytes_, i, layout_, {}, ids_, stats_, frame_).ok());
  EXPECT_FALSE(frame_.time.sensor_time_us.has_value());
}

TEST(V4l2Camera, MissingDeviceIsDisconnectedAndNonV4l2IsUnsupported) {
  V4l2Options o;
  o.device = "/dev/video-navd-does-not-exist";
  V4l2Camera missing(o);
  const IoStatus s = missing.open();
  EXPECT_EQ(s.code(), IoCode::kDisconnected) << s.message();
  EXPECT_NE(s.message().find(o.device), std::string::npos);
  o.device = "/dev/null";
  V4l2Camera not_v4l2(o);
  EXPECT_EQ(not_v4l2.open().code(), IoCode::kUnsupported);
  CameraFrame frame;
  EXPECT_FALSE(not_v4l2.grab(frame, 1ms).ok());
  EXPECT_EQ(not_v4l2.trigger().code(), IoCode::kUnsupported);
}

TEST(V4l2Camera, CapturesFromARealDevice) {
  const char* env = std::getenv("NAV_V4L2_DEVICE");
  const std::string device = env != nullptr ? env : "/dev/video0";
  if (!std::filesystem::exists(device)) {
    GTEST_SKIP() << "no V4L2 device " << device << " on this machine (set NAV_V4L2_DEVICE)";
  }
  V4l2Options o;
  o.device = device;
  V4l2Camera camera(o);
  const IoStatus s = camera.open();
  if (s.code() == IoCode::kUnsupported) GTEST_SKIP() << s.message();
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_TRUE(camera.start().ok());
  CameraFrame frame;
  const IoStatus g = camera.grab(frame, 3s);
  ASSERT_TRUE(g.ok()) << g.message();
  EXPECT_EQ(frame.image.cols, camera.layout().width);
}

}  // namespace
}  // namespace nav::drivers
