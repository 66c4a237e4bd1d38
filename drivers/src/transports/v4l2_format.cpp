// V4L2 format negotiation and per-buffer bookkeeping as pure functions (see v4l2_camera.h;
// pixel formats per the kernel's "Y16", "Y12" and "GREY" format descriptions).

#include <algorithm>

#include "nav/drivers/transports/v4l2_camera.h"

namespace nav::drivers {

IoStatus V4l2Options::validate() const {
  auto bad = [&](const std::string& what) {
    return IoStatus::Error(IoCode::kInvalidArgument, device.empty() ? "v4l2" : device, what);
  };
  if (device.empty()) return bad("options.device is empty");
  if (width <= 0 || height <= 0 || width > 65535 || height > 65535)
    return bad("options.width/height out of 1..65535");
  if (buffer_count < 2 || buffer_count > 32) return bad("options.buffer_count must be in 2..32");
  if (formats.empty()) return bad("options.formats is empty");
  for (uint32_t f : formats) {
    if (!pixel_format_from_v4l2(f))
      return bad("options.formats has an unsupported fourcc " + std::to_string(f));
  }
  return IoStatus::Ok();
}

std::optional<PixelFormat> pixel_format_from_v4l2(uint32_t fourcc_code) {
  switch (fourcc_code) {
    case kV4l2Y16:
      return PixelFormat::kMono16;
    case kV4l2Y12:
      return PixelFormat::kMono12;
    case kV4l2Grey:
      return PixelFormat::kMono8;
    default:
      return std::nullopt;
  }
}

std::optional<uint32_t> choose_v4l2_format(std::span<const uint32_t> offered,
                                           std::span<const uint32_t> preferred) {
  for (uint32_t want : preferred) {
    if (std::find(offered.begin(), offered.end(), want) != offered.end()) return want;
  }
  return std::nullopt;
}

std::optional<ImageLayout> v4l2_layout(uint32_t fourcc_code, int width, int height,
                                       uint32_t bytes_per_line) {
  const auto format = pixel_format_from_v4l2(fourcc_code);
  if (!format || width <= 0 || height <= 0) return std::nullopt;
  const std::size_t line =
      static_cast<std::size_t>(width) * (*format == PixelFormat::kMono8 ? 1 : 2);
  if (bytes_per_line != 0 && bytes_per_line < line) return std::nullopt;
  const std::size_t padding = bytes_per_line == 0 ? 0 : bytes_per_line - line;
  return ImageLayout{width, height, *format, padding};
}

IoStatus v4l2_buffer_to_frame(std::span<const uint8_t> data, const V4l2BufferInfo& info,
                              const ImageLayout& layout, const HostTime& received,
                              FrameIdUnwrapper& ids, CameraStats& stats, CameraFrame& frame) {
  if (info.error || info.bytes_used < image_bytes(layout) || data.size() < info.bytes_used) {
    ++stats.incomplete;
    return IoStatus::Error(IoCode::kInvalidArgument, "v4l2",
                           info.error
                               ? "buffer flagged V4L2_BUF_FLAG_ERROR"
                               : "buffer holds " + std::to_string(info.bytes_used) +
                                     " bytes, image needs " + std::to_string(image_bytes(layout)));
  }
  if (IoStatus s = unpack_mono(data.first(info.bytes_used), layout, frame.image); !s.ok()) {
    ++stats.unpack_errors;
    return s;
  }
  const FrameIdUnwrapper::Update id = ids.update(info.sequence);
  frame.format = layout.format;
  frame.raw_frame_id = info.sequence;
  frame.frame_id = id.id;
  frame.lost_before = id.lost;
  stats.lost += id.lost;
  if (id.restarted) ++stats.restarts;
  frame.time.host = received;
  // A monotonic buffer time stamp is on the host's clock: it is the best exposure time we have.
  frame.time.sensor_time_us =
      info.monotonic_clock ? std::optional<int64_t>(info.timestamp_us) : std::nullopt;
  frame.arrival_realtime_us = std::nullopt;
  ++stats.frames;
  return IoStatus::Ok();
}

}  // namespace nav::drivers
