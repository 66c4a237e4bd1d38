// Unpacking and packing of Mono8/12/12Packed/12p/16 images (GigE Vision GVSP pixel formats,
// EMVA PFNC 2.x); byte layouts are documented in mono_unpack.h.

#include "nav/drivers/transports/mono_unpack.h"

#include <array>
#include <cstring>
#include <opencv2/core.hpp>
#include <string>

namespace nav::drivers {
namespace {

struct FormatInfo {
  PixelFormat format;
  uint32_t pfnc;
  const char* name;
  int bits;
};

constexpr std::array<FormatInfo, 5> kFormats{{
    {PixelFormat::kMono8, 0x01080001u, "Mono8", 8},
    {PixelFormat::kMono12, 0x01100005u, "Mono12", 12},
    {PixelFormat::kMono12Packed, 0x010C0006u, "Mono12Packed", 12},
    {PixelFormat::kMono12p, 0x010C0047u, "Mono12p", 12},
    {PixelFormat::kMono16, 0x01100007u, "Mono16", 16},
}};

const FormatInfo& info(PixelFormat f) { return kFormats[static_cast<std::size_t>(f)]; }

bool is_packed(PixelFormat f) {
  return f == PixelFormat::kMono12Packed || f == PixelFormat::kMono12p;
}

/// Bytes that `n` consecutive pixels occupy starting at a byte boundary.
std::size_t bytes_for_pixels(std::size_t n, PixelFormat f) {
  if (f == PixelFormat::kMono8) return n;
  if (is_packed(f)) return 3 * (n / 2) + ((n % 2) != 0 ? 2 : 0);
  return 2 * n;
}

/// Pixel `k` of a packed run starting at `base` (both packings share the odd-pixel layout).
uint16_t packed_pixel(const uint8_t* base, std::size_t k, PixelFormat f) {
  const uint8_t* g = base + 3 * (k / 2);
  if ((k % 2) != 0) return static_cast<uint16_t>((g[2] << 4) | (g[1] >> 4));
  if (f == PixelFormat::kMono12Packed) return static_cast<uint16_t>((g[0] << 4) | (g[1] & 0x0F));
  return static_cast<uint16_t>(g[0] | ((g[1] & 0x0F) << 8));  // Mono12p, LSB first
}

void set_packed_pixel(uint8_t* base, std::size_t k, PixelFormat f, uint16_t v) {
  uint8_t* g = base + 3 * (k / 2);
  v &= 0x0FFF;
  if ((k % 2) != 0) {
    g[2] = static_cast<uint8_t>(v >> 4);
    g[1] = static_cast<uint8_t>((g[1] & 0x0F) | ((v & 0x0F) << 4));
  } else if (f == PixelFormat::kMono12Packed) {
    g[0] = static_cast<uint8_t>(v >> 4);
    g[1] = static_cast<uint8_t>((g[1] & 0xF0) | (v & 0x0F));
  } else {
    g[0] = static_cast<uint8_t>(v & 0xFF);
    g[1] = static_cast<uint8_t>((g[1] & 0xF0) | (v >> 8));
  }
}

/// Where line `r` starts: a byte pointer plus the index of its first pixel relative to it.
struct LineStart {
  std::size_t byte_offset;
  std::size_t first_pixel;
};

LineStart line_start(const ImageLayout& l, int r) {
  const auto row = static_cast<std::size_t>(r);
  const auto w = static_cast<std::size_t>(l.width);
  if (l.line_padding_bytes > 0) {
    return {row * (bytes_for_pixels(w, l.format) + l.line_padding_bytes), 0};
  }
  if (is_packed(l.format)) return {0, row * w};  // contiguous bit stream across lines
  return {bytes_for_pixels(row * w, l.format), 0};
}

}  // namespace

uint32_t pfnc_code(PixelFormat format) { return info(format).pfnc; }

std::optional<PixelFormat> pixel_format_from_pfnc(uint32_t code) {
  for (const FormatInfo& f : kFormats) {
    if (f.pfnc == code) return f.format;
  }
  return std::nullopt;
}

const char* genicam_name(PixelFormat format) { return info(format).name; }

std::optional<PixelFormat> pixel_format_from_name(const char* name) {
  if (name == nullptr) return std::nullopt;
  for (const FormatInfo& f : kFormats) {
    if (std::strcmp(f.name, name) == 0) return f.format;
  }
  return std::nullopt;
}

int significant_bits(PixelFormat format) { return info(format).bits; }

int unpacked_cv_type(PixelFormat format) {
  return format == PixelFormat::kMono8 ? CV_8UC1 : CV_16UC1;
}

std::size_t image_bytes(const ImageLayout& l) {
  if (l.width <= 0 || l.height <= 0) return 0;
  const auto w = static_cast<std::size_t>(l.width);
  const auto h = static_cast<std::size_t>(l.height);
  if (l.line_padding_bytes == 0) return bytes_for_pixels(w * h, l.format);
  // The last line's padding is not required (some senders trim it).
  return (h - 1) * (bytes_for_pixels(w, l.format) + l.line_padding_bytes) +
         bytes_for_pixels(w, l.format);
}

IoStatus unpack_mono(std::span<const uint8_t> data, const ImageLayout& l, cv::Mat& out) {
  const std::size_t needed = image_bytes(l);
  if (needed == 0) {
    return IoStatus::Error(
        IoCode::kInvalidArgument, "image",
        "layout " + std::to_string(l.width) + "x" + std::to_string(l.height) + " is not positive");
  }
  if (data.size() < needed) {
    return IoStatus::Error(IoCode::kInvalidArgument, "image",
                           std::string(genicam_name(l.format)) + " " + std::to_string(l.width) +
                               "x" + std::to_string(l.height) + " needs " + std::to_string(needed) +
                               " bytes, buffer has " + std::to_string(data.size()));
  }
  out.create(l.height, l.width, unpacked_cv_type(l.format));
  const auto w = static_cast<std::size_t>(l.width);
  for (int r = 0; r < l.height; ++r) {
    const LineStart s = line_start(l, r);
    const uint8_t* src = data.data() + s.byte_offset;
    if (l.format == PixelFormat::kMono8) {
      std::memcpy(out.ptr<uint8_t>(r), src, w);
      continue;
    }
    auto* dst = out.ptr<uint16_t>(r);
    if (is_packed(l.format)) {
      for (std::size_t c = 0; c < w; ++c) dst[c] = packed_pixel(src, s.first_pixel + c, l.format);
    } else {  // little-endian 16-bit words, assembled bytewise (host-endian independent)
      const uint16_t mask = l.format == PixelFormat::kMono12 ? 0x0FFF : 0xFFFF;
      for (std::size_t c = 0; c < w; ++c) {
        dst[c] = static_cast<uint16_t>((src[2 * c] | (src[2 * c + 1] << 8)) & mask);
      }
    }
  }
  return IoStatus::Ok();
}

std::vector<uint8_t> pack_mono(const cv::Mat& image, const ImageLayout& l) {
  if (image.rows != l.height || image.cols != l.width ||
      image.type() != unpacked_cv_type(l.format) || image_bytes(l) == 0) {
    return {};
  }
  const std::size_t padded_total =
      l.line_padding_bytes == 0 ? image_bytes(l) : image_bytes(l) + l.line_padding_bytes;
  std::vector<uint8_t> bytes(padded_total, 0);
  const auto w = static_cast<std::size_t>(l.width);
  for (int r = 0; r < l.height; ++r) {
    const LineStart s = line_start(l, r);
    uint8_t* dst = bytes.data() + s.byte_offset;
    if (l.format == PixelFormat::kMono8) {
      std::memcpy(dst, image.ptr<uint8_t>(r), w);
      continue;
    }
    const auto* src = image.ptr<uint16_t>(r);
    for (std::size_t c = 0; c < w; ++c) {
      if (is_packed(l.format)) {
        set_packed_pixel(dst, s.first_pixel + c, l.format, src[c]);
      } else {
        const uint16_t v = l.format == PixelFormat::kMono12 ? (src[c] & 0x0FFF) : src[c];
        dst[2 * c] = static_cast<uint8_t>(v & 0xFF);
        dst[2 * c + 1] = static_cast<uint8_t>(v >> 8);
      }
    }
  }
  return bytes;
}

}  // namespace nav::drivers
