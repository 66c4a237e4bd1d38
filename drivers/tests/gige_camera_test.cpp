// GigeCamera on Aravis' fake cameras: in process ("Fake" interface), as a real GigE Vision
// device on loopback (GVCP/GVSP through the network stack), with the stock fake's Mono8/Mono16
// and, through a GenICam description extended with Mono12/Mono12Packed, with 12-bit frames the
// test serves itself (arv_fake_camera_set_fill_pattern), and 16-bit block-id wrap-around (the
// fake starts its ids at 65400). The GigE-on-loopback cases are in gige_loopback_test.cpp.

#include "nav/drivers/transports/gige_camera.h"

#include <arv.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <string>

#include "fake_camera_pattern.h"

namespace nav::drivers {
namespace {

using namespace std::chrono_literals;
using nav::testing::expect_pattern_stream;
using nav::testing::serve_pattern;

GigeOptions fake_options(PixelFormat format) {
  GigeOptions o;
  o.camera_id = "Fake_1";
  o.pixel_format = format;
  o.exposure_us = 1000.0;
  o.gain = 2.0;
  o.frame_rate_hz = 500.0;  // 135 frames from the fake's first id (65400) to the wrap
  o.buffer_count = 16;
  return o;
}

class GigeCameraFake : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { arv_enable_interface("Fake"); }
};

TEST(GigeOptions, ValidateNamesTheBadField) {
  GigeOptions o;
  EXPECT_TRUE(o.validate().ok());
  o.exposure_us = -1.0;
  EXPECT_NE(o.validate().message().find("exposure_us"), std::string::npos);
  o = GigeOptions{};
  o.buffer_count = 1;
  EXPECT_NE(o.validate().message().find("buffer_count"), std::string::npos);
  o = GigeOptions{};
  o.width = 640;  // height left 0
  EXPECT_NE(o.validate().message().find("region"), std::string::npos);
  o = GigeOptions{};
  o.packet_size_bytes = 100;
  EXPECT_NE(o.validate().message().find("packet_size_bytes"), std::string::npos);
  o = GigeOptions{};
  o.frame_id_bits = 32;
  EXPECT_FALSE(o.validate().ok());
  o = GigeOptions{};
  o.trigger_mode = TriggerMode::kHardware;
  o.trigger_source.clear();
  EXPECT_FALSE(o.validate().ok());
}

TEST_F(GigeCameraFake, UnknownIdIsReportedAsDisconnected) {
  GigeOptions o = fake_options(PixelFormat::kMono8);
  o.camera_id = "Fake_NoSuchCamera";
  GigeCamera camera(o);
  const IoStatus s = camera.open();
  EXPECT_EQ(s.code(), IoCode::kDisconnected) << s.message();
  EXPECT_NE(s.message().find("Fake_NoSuchCamera"), std::string::npos);
  CameraFrame frame;
  EXPECT_FALSE(camera.grab(frame, 1ms).ok());
  EXPECT_FALSE(camera.start().ok());
}

TEST_F(GigeCameraFake, RefusesAPixelFormatTheCameraLacks) {
  GigeCamera camera(fake_options(PixelFormat::kMono12Packed));  // the stock fake has no Mono12
  const IoStatus s = camera.open();
  EXPECT_EQ(s.code(), IoCode::kUnsupported) << s.message();
  EXPECT_NE(s.message().find("Mono12Packed"), std::string::npos);
}

TEST_F(GigeCameraFake, Mono16FramesCarryPixelsIdsAndTimestampsAcrossTheIdWrap) {
  GigeCamera camera(fake_options(PixelFormat::kMono16));
  ASSERT_TRUE(camera.open().ok());
  size_t capacity = 0;
  serve_pattern(camera, capacity);
  ASSERT_TRUE(camera.start().ok());
  expect_pattern_stream(camera, PixelFormat::kMono16, 160, true);
  camera.stop();
  CameraFrame frame;
  EXPECT_EQ(camera.grab(frame, 1ms).code(), IoCode::kInvalidArgument);  // stopped: refused
}

TEST_F(GigeCameraFake, Mono8StreamIsEightBit) {
  GigeCamera camera(fake_options(PixelFormat::kMono8));
  ASSERT_TRUE(camera.open().ok());
  size_t capacity = 0;
  serve_pattern(camera, capacity);
  ASSERT_TRUE(camera.start().ok());
  expect_pattern_stream(camera, PixelFormat::kMono8, 5, false);
}

/// The stock fake's GenICam XML with Mono12 and Mono12Packed added to PixelFormat (the fake's
/// payload and buffer layout follow the bits-per-pixel field of the PFNC code).
std::filesystem::path write_mono12_genicam() {
  ArvFakeCamera* probe = arv_fake_camera_new("probe");
  size_t size = 0;
  const char* text = arv_fake_camera_get_genicam_xml(probe, &size);
  std::string xml(text, size);
  g_object_unref(probe);
  const std::string anchor = "<pValue>PixelFormatRegister</pValue>";
  const auto at = xml.find(anchor);
  if (at == std::string::npos) return {};
  xml.insert(
      at,
      "<EnumEntry Name=\"Mono12\" NameSpace=\"Standard\"><Value>17825797</Value></EnumEntry>\n"
      "<EnumEntry Name=\"Mono12Packed\" "
      "NameSpace=\"Standard\"><Value>17563654</Value></EnumEntry>\n");
  const auto path = std::filesystem::temp_directory_path() /
                    ("navd_fake_mono12_" + std::to_string(::getpid()) + ".xml");
  std::ofstream(path) << xml;
  return path;
}

TEST_F(GigeCameraFake, TwelveBitFormatsThroughACustomGenicamDescription) {
  const auto xml = write_mono12_genicam();
  ASSERT_FALSE(xml.empty()) << "stock fake XML has no PixelFormatRegister anchor";
  arv_set_fake_camera_genicam_filename(xml.c_str());
  for (PixelFormat format : {PixelFormat::kMono12Packed, PixelFormat::kMono12}) {
    GigeOptions o = fake_options(format);
    o.offset_x = 2;
    o.offset_y = 3;
    o.width = 333;  // odd: with Mono12Packed, line 1 starts in the middle of a 3-byte group
    o.height = 20;
    GigeCamera camera(o);
    const IoStatus s = camera.open();
    ASSERT_TRUE(s.ok()) << s.message();
    size_t capacity = 0;
    serve_pattern(camera, capacity);
    ASSERT_TRUE(camera.start().ok());
    EXPECT_EQ(camera.width(), 333);
    EXPECT_EQ(camera.height(), 20);
    expect_pattern_stream(camera, format, 4, false);
  }
  arv_set_fake_camera_genicam_filename(nullptr);
  std::filesystem::remove(xml);
}

}  // namespace
}  // namespace nav::drivers
