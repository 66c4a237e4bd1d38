#pragma once
// Monochrome pixel formats of machine-vision cameras and their unpacking to cv::Mat.
// Layouts follow the GigE Vision 1.x GVSP pixel formats and the EMVA GenICam Pixel Format
// Naming Convention (PFNC 2.x):
//   Mono8         0x01080001  one byte per pixel                          -> CV_8UC1
//   Mono12        0x01100005  uint16 little endian, value in bits 11..0   -> CV_16UC1 (0..4095;
//                             bits 15..12 must be zero and are masked off)
//   Mono16        0x01100007  uint16 little endian                        -> CV_16UC1
//   Mono12Packed  0x010C0006  GigE Vision packing, 2 pixels in 3 bytes:
//                             B0 = p0[11:4], B1 = p1[3:0] << 4 | p0[3:0], B2 = p1[11:4]
//   Mono12p       0x010C0047  PFNC LSB-first bit packing, 2 pixels in 3 bytes:
//                             B0 = p0[7:0],  B1 = p1[3:0] << 4 | p0[11:8], B2 = p1[11:4]
// 12-bit values are kept as 0..4095 (not shifted to 16 bits): radiometric calibration of the
// 12-bit CCD (Eustice et al. 2005, Table II) works on the sensor's own counts.
//
// Line layout: with line_padding_bytes == 0 the lines follow each other without gaps (for the
// packed formats an odd width makes the next line start in the middle of a 3-byte group, as
// GigE Vision specifies); with padding > 0 every line starts on a byte boundary and is followed
// by that many padding bytes (GVSP x-padding).
//
// Pure functions: no allocation when `out` already has the right size and type.

#include <cstddef>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <span>
#include <vector>

#include "nav/drivers/transports/io_status.h"

namespace nav::drivers {

enum class PixelFormat { kMono8, kMono12, kMono12Packed, kMono12p, kMono16 };

struct ImageLayout {
  int width = 0;   ///< pixels, > 0
  int height = 0;  ///< lines, > 0
  PixelFormat format = PixelFormat::kMono16;
  std::size_t line_padding_bytes = 0;  ///< bytes after each line (0: lines are contiguous)
};

/// PFNC / GigE Vision pixel format code, and back (nullopt for formats we do not unpack).
uint32_t pfnc_code(PixelFormat format);
std::optional<PixelFormat> pixel_format_from_pfnc(uint32_t code);
/// GenICam PixelFormat enumeration entry name ("Mono12Packed", ...), and back.
const char* genicam_name(PixelFormat format);
std::optional<PixelFormat> pixel_format_from_name(const char* name);
/// Significant bits per pixel value (8, 12 or 16).
int significant_bits(PixelFormat format);
/// OpenCV type of the unpacked image: CV_8UC1 for Mono8, CV_16UC1 otherwise.
int unpacked_cv_type(PixelFormat format);

/// Bytes one image of `layout` occupies; 0 when width/height are not positive.
std::size_t image_bytes(const ImageLayout& layout);

/// Unpacks `data` into `out` (re-created only if its size/type differ). kInvalidArgument when
/// the layout is not positive or `data` is shorter than image_bytes(layout); `out` is then
/// left unchanged. Extra trailing bytes (e.g. chunk data) are ignored.
IoStatus unpack_mono(std::span<const uint8_t> data, const ImageLayout& layout, cv::Mat& out);

/// Packs a CV_16UC1 (or CV_8UC1 for Mono8) image into `layout.format` — the inverse of
/// unpack_mono, for tests and the survey simulator. Values above the format's range are
/// truncated to their low bits. Returns an empty vector if the image does not match the layout.
std::vector<uint8_t> pack_mono(const cv::Mat& image, const ImageLayout& layout);

}  // namespace nav::drivers
