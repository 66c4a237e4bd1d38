// Unpacking of Mono8/12/12Packed/12p/16 camera buffers (GigE Vision GVSP, EMVA PFNC) on
// hand-built buffers whose bytes are derived in the comments, then odd widths, line padding,
// short buffers, and pack/unpack round trips over many shapes.

#include <arv.h>
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <random>

#include "nav/drivers/transports/mono_unpack.h"

namespace nav::drivers {
namespace {

std::vector<uint16_t> pixels(const cv::Mat& m) {
  std::vector<uint16_t> v;
  for (int r = 0; r < m.rows; ++r) {
    for (int c = 0; c < m.cols; ++c)
      v.push_back(m.type() == CV_8UC1 ? m.at<uint8_t>(r, c) : m.at<uint16_t>(r, c));
  }
  return v;
}

TEST(Mono12Unpack, PfncCodesMatchAravis) {
  EXPECT_EQ(pfnc_code(PixelFormat::kMono8), ARV_PIXEL_FORMAT_MONO_8);
  EXPECT_EQ(pfnc_code(PixelFormat::kMono12), ARV_PIXEL_FORMAT_MONO_12);
  EXPECT_EQ(pfnc_code(PixelFormat::kMono12Packed), ARV_PIXEL_FORMAT_MONO_12_PACKED);
  EXPECT_EQ(pfnc_code(PixelFormat::kMono16), ARV_PIXEL_FORMAT_MONO_16);
  EXPECT_EQ(pixel_format_from_pfnc(0x010C0047u), PixelFormat::kMono12p);
  EXPECT_FALSE(pixel_format_from_pfnc(ARV_PIXEL_FORMAT_RGB_8_PACKED).has_value());
  EXPECT_EQ(pixel_format_from_name("Mono12Packed"), PixelFormat::kMono12Packed);
  EXPECT_FALSE(pixel_format_from_name("RGB8").has_value());
}

TEST(Mono12Unpack, GigeVisionPackedTwoPixels) {
  // p0 = 0xABC, p1 = 0x123: B0 = p0[11:4] = 0xAB, B1 = p1[3:0]<<4 | p0[3:0] = 0x3C,
  // B2 = p1[11:4] = 0x12.
  const uint8_t bytes[] = {0xAB, 0x3C, 0x12};
  cv::Mat out;
  ASSERT_TRUE(unpack_mono(bytes, {2, 1, PixelFormat::kMono12Packed, 0}, out).ok());
  EXPECT_EQ(out.type(), CV_16UC1);
  EXPECT_EQ(pixels(out), (std::vector<uint16_t>{0xABC, 0x123}));
}

TEST(Mono12Unpack, PfncMono12pTwoPixels) {
  // p0 = 0xABC, p1 = 0x123, LSB first: B0 = p0[7:0] = 0xBC, B1 = p1[3:0]<<4 | p0[11:8] = 0x3A,
  // B2 = p1[11:4] = 0x12.
  const uint8_t bytes[] = {0xBC, 0x3A, 0x12};
  cv::Mat out;
  ASSERT_TRUE(unpack_mono(bytes, {2, 1, PixelFormat::kMono12p, 0}, out).ok());
  EXPECT_EQ(pixels(out), (std::vector<uint16_t>{0xABC, 0x123}));
}

TEST(Mono12Unpack, OddWidthContiguousLinesStartMidGroup) {
  // 3x2 image, lines packed back to back (GigE Vision: line 1 starts inside group 1).
  // pixels 0xFFF 0x800 0x001 | 0x7FE 0x0F0 0xA5A
  // g0 (0xFFF,0x800): FF 0F 80   g1 (0x001,0x7FE): 00 E1 7F   g2 (0x0F0,0xA5A): 0F A0 A5
  const uint8_t bytes[] = {0xFF, 0x0F, 0x80, 0x00, 0xE1, 0x7F, 0x0F, 0xA0, 0xA5};
  const ImageLayout layout{3, 2, PixelFormat::kMono12Packed, 0};
  EXPECT_EQ(image_bytes(layout), 9u);
  cv::Mat out;
  ASSERT_TRUE(unpack_mono(bytes, layout, out).ok());
  EXPECT_EQ(pixels(out), (std::vector<uint16_t>{0xFFF, 0x800, 0x001, 0x7FE, 0x0F0, 0xA5A}));
}

TEST(Mono12Unpack, PaddedLinesStartOnByteBoundaries) {
  // 3x2, 2 padding bytes per line: a line is 3 + 2 bytes (the odd last pixel takes 2), stride 7.
  // line 0: 0x123 0x456 0x789 -> 12 63 45 | 78 09 | EE EE
  // line 1: 0xABC 0xDEF 0x010 -> AB FC DE | 01 00
  const uint8_t bytes[] = {0x12, 0x63, 0x45, 0x78, 0x09, 0xEE, 0xEE, 0xAB, 0xFC, 0xDE, 0x01, 0x00};
  const ImageLayout layout{3, 2, PixelFormat::kMono12Packed, 2};
  EXPECT_EQ(image_bytes(layout), 12u);
  cv::Mat out;
  ASSERT_TRUE(unpack_mono(bytes, layout, out).ok());
  EXPECT_EQ(pixels(out), (std::vector<uint16_t>{0x123, 0x456, 0x789, 0xABC, 0xDEF, 0x010}));
}

TEST(Mono12Unpack, SixteenBitLittleEndianAndMono12Masking) {
  const uint8_t bytes[] = {0x34, 0x12, 0xFF, 0xFF};
  cv::Mat out;
  ASSERT_TRUE(unpack_mono(bytes, {2, 1, PixelFormat::kMono16, 0}, out).ok());
  EXPECT_EQ(pixels(out), (std::vector<uint16_t>{0x1234, 0xFFFF}));
  ASSERT_TRUE(unpack_mono(bytes, {2, 1, PixelFormat::kMono12, 0}, out).ok());
  EXPECT_EQ(pixels(out), (std::vector<uint16_t>{0x0234, 0x0FFF}));  // bits 15..12 masked off
}

TEST(Mono12Unpack, Mono8WithPaddingIsCV8U) {
  const uint8_t bytes[] = {1, 2, 0, 3, 4};  // 2x2, one padding byte after line 0
  cv::Mat out;
  ASSERT_TRUE(unpack_mono(bytes, {2, 2, PixelFormat::kMono8, 1}, out).ok());
  EXPECT_EQ(out.type(), CV_8UC1);
  EXPECT_EQ(pixels(out), (std::vector<uint16_t>{1, 2, 3, 4}));
}

TEST(Mono12Unpack, ShortBufferOrBadLayoutFailsAndLeavesOutputUnchanged) {
  cv::Mat out(1, 1, CV_16UC1, cv::Scalar(77));
  const uint8_t bytes[8] = {};
  const IoStatus s = unpack_mono(std::span(bytes, 8), {3, 2, PixelFormat::kMono12Packed, 0}, out);
  EXPECT_EQ(s.code(), IoCode::kInvalidArgument);
  EXPECT_NE(s.message().find("needs 9 bytes, buffer has 8"), std::string::npos);
  EXPECT_FALSE(unpack_mono(bytes, {0, 2, PixelFormat::kMono16, 0}, out).ok());
  EXPECT_FALSE(unpack_mono(bytes, {2, -1, PixelFormat::kMono16, 0}, out).ok());
  EXPECT_FALSE(unpack_mono({}, {1, 1, PixelFormat::kMono8, 0}, out).ok());
  ASSERT_EQ(out.rows, 1);
  EXPECT_EQ(out.at<uint16_t>(0, 0), 77);
}

TEST(Mono12Unpack, ReusesTheOutputBuffer) {
  const ImageLayout layout{64, 48, PixelFormat::kMono12Packed, 0};
  const std::vector<uint8_t> bytes(image_bytes(layout), 0x5A);
  cv::Mat out;
  ASSERT_TRUE(unpack_mono(bytes, layout, out).ok());
  const uint8_t* first = out.data;
  ASSERT_TRUE(unpack_mono(bytes, layout, out).ok());
  EXPECT_EQ(out.data, first);
}

TEST(Mono12Unpack, PackUnpackRoundTripsEveryFormatWidthAndPadding) {
  std::mt19937 rng(7);
  for (PixelFormat f : {PixelFormat::kMono8, PixelFormat::kMono12, PixelFormat::kMono12Packed,
                        PixelFormat::kMono12p, PixelFormat::kMono16}) {
    const int max_value = (1 << significant_bits(f)) - 1;
    for (int width = 1; width <= 9; ++width) {
      for (std::size_t padding : {std::size_t{0}, std::size_t{1}, std::size_t{4}}) {
        const ImageLayout layout{width, 5, f, padding};
        cv::Mat image(5, width, unpacked_cv_type(f));
        for (int r = 0; r < 5; ++r) {
          for (int c = 0; c < width; ++c) {
            const int v = static_cast<int>(rng() % static_cast<unsigned>(max_value + 1));
            if (f == PixelFormat::kMono8)
              image.at<uint8_t>(r, c) = static_cast<uint8_t>(v);
            else
              image.at<uint16_t>(r, c) = static_cast<uint16_t>(v);
          }
        }
        const std::vector<uint8_t> bytes = pack_mono(image, layout);
        ASSERT_GE(bytes.size(), image_bytes(layout)) << genicam_name(f) << " w=" << width;
        cv::Mat out;
        ASSERT_TRUE(unpack_mono(bytes, layout, out).ok());
        EXPECT_EQ(cv::norm(image, out, cv::NORM_INF), 0.0)
            << genicam_name(f) << " w=" << width << " pad=" << padding;
      }
    }
  }
}

}  // namespace
}  // namespace nav::drivers
