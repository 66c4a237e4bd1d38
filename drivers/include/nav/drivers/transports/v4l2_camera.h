#pragma once
// V4L2 video capture (Linux Media Infrastructure API, "Video for Linux API": VIDIOC_QUERYCAP,
// VIDIOC_ENUM_FMT/S_FMT, memory-mapped streaming I/O with VIDIOC_REQBUFS/QBUF/DQBUF) for 16-bit
// grey cameras (V4L2_PIX_FMT_Y16, V4L2_PIX_FMT_Y12 — 12 bits in a little-endian 16-bit word —
// and GREY). Each dequeued buffer is converted into a CameraFrame on the driver thread and
// queued back at once, so the kernel never runs out of buffers because of us.
//
// The format negotiation and the per-buffer bookkeeping (sequence gaps, error flag, time stamps,
// line padding) are pure functions below, tested without a device; the device test skips when
// there is no /dev/video*.
//
// Threading: one driver thread calls open()/start()/grab()/stop()/close() (see camera.h).

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "nav/drivers/transports/camera.h"

namespace nav::drivers {

/// V4L2 four-character codes we capture (values of V4L2_PIX_FMT_*).
inline constexpr uint32_t fourcc(char a, char b, char c, char d) {
  return static_cast<uint32_t>(a) | (static_cast<uint32_t>(b) << 8) |
         (static_cast<uint32_t>(c) << 16) | (static_cast<uint32_t>(d) << 24);
}
inline constexpr uint32_t kV4l2Y16 = fourcc('Y', '1', '6', ' ');
inline constexpr uint32_t kV4l2Y12 = fourcc('Y', '1', '2', ' ');
inline constexpr uint32_t kV4l2Grey = fourcc('G', 'R', 'E', 'Y');

struct V4l2Options {
  std::string device = "/dev/video0";
  int width = 1360;  ///< requested pixels; the driver may adjust, the result is reported
  int height = 1024;
  /// Formats in order of preference; the first one the device offers is used.
  std::vector<uint32_t> formats{kV4l2Y16, kV4l2Y12, kV4l2Grey};
  /// Memory-mapped buffers requested, 2..32 (the driver may grant more or fewer, at least 2).
  int buffer_count = 4;

  IoStatus validate() const;
};

/// Our pixel format for a V4L2 fourcc (Y16 -> Mono16, Y12 -> Mono12, GREY -> Mono8).
std::optional<PixelFormat> pixel_format_from_v4l2(uint32_t fourcc_code);
/// First entry of `preferred` that the device `offered`, or nullopt.
std::optional<uint32_t> choose_v4l2_format(std::span<const uint32_t> offered,
                                           std::span<const uint32_t> preferred);
/// Image layout for a negotiated format; nullopt when bytes_per_line is shorter than a line.
std::optional<ImageLayout> v4l2_layout(uint32_t fourcc_code, int width, int height,
                                       uint32_t bytes_per_line);

/// What a dequeued V4L2 buffer says about itself (fields of struct v4l2_buffer).
struct V4l2BufferInfo {
  uint32_t sequence = 0;
  bool error = false;            ///< V4L2_BUF_FLAG_ERROR: data may be corrupt
  bool monotonic_clock = false;  ///< V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC
  int64_t timestamp_us = 0;      ///< buffer time stamp (start of frame for most drivers)
  uint32_t bytes_used = 0;
};

/// Converts one dequeued buffer into `frame` (pixels, unwrapped sequence, time stamps) and
/// updates `stats`. The V4L2 time stamp is host CLOCK_MONOTONIC: it becomes
/// frame.time.sensor_time_us (the camera has no clock of its own here). kInvalidArgument for a
/// buffer flagged as erroneous or too short (counted as incomplete); `frame` untouched then.
IoStatus v4l2_buffer_to_frame(std::span<const uint8_t> data, const V4l2BufferInfo& info,
                              const ImageLayout& layout, const HostTime& received,
                              FrameIdUnwrapper& ids, CameraStats& stats, CameraFrame& frame);

class V4l2Camera final : public Camera {
 public:
  explicit V4l2Camera(V4l2Options options);
  ~V4l2Camera() override;
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  /// Opens the device, negotiates the format and maps the buffers. kDisconnected when the
  /// device node is missing, kUnsupported when it is not a streaming capture device or offers
  /// none of the formats.
  IoStatus open();
  void close();

  IoStatus start() override;
  void stop() override;
  IoStatus grab(CameraFrame& frame, std::chrono::milliseconds timeout) override;
  /// V4L2 has no software trigger: kUnsupported (use GpioLines to trigger the camera).
  IoStatus trigger() override;
  CameraStats stats() const override { return stats_; }
  const std::string& name() const override { return options_.device; }

  const ImageLayout& layout() const { return layout_; }

 private:
  IoStatus negotiate_format();
  IoStatus map_buffers();
  IoStatus fail(int err, const std::string& what);

  struct Mapping {
    void* start = nullptr;
    std::size_t length = 0;
  };
  V4l2Options options_;
  IoStatus options_status_;
  int fd_ = -1;
  bool streaming_ = false;
  uint32_t fourcc_ = 0;
  ImageLayout layout_;
  std::vector<Mapping> buffers_;
  FrameIdUnwrapper ids_{32, false};
  CameraStats stats_;
};

}  // namespace nav::drivers
