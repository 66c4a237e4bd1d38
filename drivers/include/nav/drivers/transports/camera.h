#pragma once
// Camera transport interface shared by the GigE Vision (Aravis) and V4L2 back ends: a grabbed
// frame is an owned 8/16-bit cv::Mat with the camera's frame id (unwrapped to 64 bits), the
// camera's own time stamp and the host receive times; lost and incomplete frames are counted.
// The vision thread of navd consumes CameraFrame; replay and tests implement Camera directly.
//
// Threading: start()/stop()/grab()/trigger() are called by ONE driver thread. grab() blocks for
// at most its timeout and does the unpacking itself, so back-end threads (the Aravis stream
// thread, the kernel) only ever fill buffers.

#include <chrono>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>

#include "nav/drivers/time/timestamps.h"
#include "nav/drivers/transports/io_status.h"
#include "nav/drivers/transports/mono_unpack.h"

namespace nav::drivers {

struct CameraFrame {
  cv::Mat
      image;  ///< CV_16UC1 (Mono12*, Mono16: sensor counts) or CV_8UC1 (Mono8); reused by grab()
  PixelFormat format = PixelFormat::kMono16;
  uint64_t frame_id = 0;      ///< unwrapped, strictly increasing while the stream runs
  uint64_t raw_frame_id = 0;  ///< as sent by the device (GVSP block id, V4L2 sequence)
  uint64_t lost_before = 0;   ///< frames missing between the previous frame and this one
  /// time.sensor_time_us: the camera's time stamp of the frame (device clock, µs) when it has
  /// one; time.host: host clocks when grab() received the completed buffer.
  Timestamps time;
  /// Host CLOCK_REALTIME (µs) at which the back end saw the frame arrive (Aravis system time
  /// stamp, V4L2 buffer time stamp), closer to the exposure than time.host; nullopt if none.
  std::optional<int64_t> arrival_realtime_us;
};

struct CameraStats {
  uint64_t frames = 0;      ///< complete frames returned by grab()
  uint64_t incomplete = 0;  ///< buffers dropped because incomplete (missing packets, timeout, size)
  uint64_t lost = 0;        ///< frames never seen (gaps in the frame id)
  uint64_t underruns = 0;   ///< frames the back end dropped for lack of a free buffer
  uint64_t unpack_errors = 0;  ///< complete buffers whose layout did not match the pixel format
  uint64_t restarts = 0;       ///< frame id went backwards (camera restarted its counter)
};

class Camera {
 public:
  virtual ~Camera() = default;
  /// Starts streaming (buffers queued, acquisition on).
  virtual IoStatus start() = 0;
  /// Stops streaming; idempotent.
  virtual void stop() = 0;
  /// Next complete frame into `frame` (its image buffer is reused), waiting at most `timeout`.
  virtual IoStatus grab(CameraFrame& frame, std::chrono::milliseconds timeout) = 0;
  /// Software trigger (trigger mode kSoftware); kUnsupported where the back end has none.
  virtual IoStatus trigger() = 0;
  virtual CameraStats stats() const = 0;
  virtual const std::string& name() const = 0;
};

/// Unwraps a camera's N-bit frame counter into a 64-bit id and reports gaps. GigE Vision 1.x
/// block ids are 16 bits and skip 0 on wrap-around (1 ... 65535, 1, ...; GigE Vision 1.2
/// section "GVSP block_id"); extended ids (GEV 2.0) are 64 bits; V4L2 sequences are 32 bits
/// starting at 0. A jump backwards by more than half the period is taken as a restart.
class FrameIdUnwrapper {
 public:
  struct Update {
    uint64_t id = 0;    ///< unwrapped id
    uint64_t lost = 0;  ///< ids skipped since the previous update
    bool restarted = false;
    bool duplicate = false;  ///< same raw id as the previous update
  };

  /// `bits` in 1..64; `zero_reserved` when the counter never takes the value 0.
  explicit FrameIdUnwrapper(int bits = 16, bool zero_reserved = true);
  Update update(uint64_t raw_id);
  void reset() { started_ = false; }

 private:
  uint64_t ordinal(uint64_t raw) const;

  int bits_;
  bool zero_reserved_;
  uint64_t period_;  ///< number of distinct ids; 0 stands for 2^64
  bool started_ = false;
  uint64_t last_ordinal_ = 0;
  uint64_t last_id_ = 0;
};

}  // namespace nav::drivers
