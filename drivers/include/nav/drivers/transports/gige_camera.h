#pragma once
// GigE Vision / GenICam camera through Aravis 0.8 (https://aravisproject.github.io/aravis/):
// discovery by device id, pixel format (Mono8/Mono12/Mono12Packed/Mono12p/Mono16), exposure,
// gain and trigger mode from GigeOptions, streaming into a fixed pool of buffers, unpacking to
// cv::Mat, device and host time stamps, 16-bit GVSP block-id wrap-around, and counters of
// incomplete, lost and underrun buffers.
//
// Aravis stream-thread rules: the stream is created without a callback, so nothing of ours runs
// on Aravis' stream thread; grab() pops a filled buffer on the driver thread, copies/unpacks
// it, and pushes the buffer back to the stream before returning, so the pool never drains. A
// "control-lost" signal (heartbeat failure: cable pulled, camera power lost) only sets a flag
// from Aravis' thread; grab() then reports kDisconnected and the driver reopens. The heartbeat
// takes about 6 s to give up, so grab() also probes the control channel itself whenever no
// frame has arrived for `liveness_probe_period_ms` (gvcp_probe.h): a camera that answers none
// of its reads is reported kDisconnected within about a second.
//
// Threading: open()/start()/grab()/trigger()/stop() from one driver thread (see camera.h).

#include <atomic>
#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "nav/drivers/transports/camera.h"

struct _ArvCamera;
struct _ArvStream;
struct _ArvBuffer;

namespace nav::drivers {

class GvcpProbe;

enum class TriggerMode {
  kFreeRun,   ///< camera runs at frame_rate_hz
  kSoftware,  ///< one frame per Camera::trigger()
  kHardware,  ///< one frame per edge on trigger_source (e.g. "Line1" driven by GpioLines)
};

struct GigeOptions {
  /// Aravis device id: "<vendor>-<model>-<serial>", a user-defined name, an IP address, or
  /// "Fake_1" for the in-process fake. Empty: the first camera found.
  std::string camera_id;
  PixelFormat pixel_format = PixelFormat::kMono12Packed;
  /// Exposure time in µs, > 0 (feature ExposureTime / ExposureTimeAbs).
  double exposure_us = 10'000.0;
  /// Gain in the camera's unit (dB for Gain, raw counts for GainRaw); nullopt leaves it as is.
  std::optional<double> gain;
  TriggerMode trigger_mode = TriggerMode::kFreeRun;
  /// Trigger input for kHardware, e.g. "Line1".
  std::string trigger_source = "Line1";
  /// Free-running frame rate in Hz; 0 leaves the camera's setting.
  double frame_rate_hz = 0.0;
  /// Region of interest in sensor pixels; width/height 0 keep the camera's current frame. The
  /// camera may round to its increments: width()/height() report what it set.
  int offset_x = 0;
  int offset_y = 0;
  int width = 0;
  int height = 0;
  /// GVSP packet size in bytes (GevSCPSPacketSize), 576..65535; 0 negotiates the largest packet
  /// the network path carries (jumbo frames on a dedicated camera NIC).
  int packet_size_bytes = 0;
  /// Buffers queued to the stream, 2..256. More buffers absorb longer vision-thread stalls.
  int buffer_count = 8;
  /// Width of the device frame counter: 16 for GigE Vision 1.x block ids (0 skipped on wrap),
  /// 64 for extended ids.
  int frame_id_bits = 16;
  /// Without a frame for this long grab() reads a register of the device (one probe) to see
  /// that it is still there; 0: no probe (only Aravis' heartbeat, ~6 s). [0, 60000] ms.
  int liveness_probe_period_ms = 500;
  /// A probe fails after this many unanswered reads of `liveness_probe_timeout_ms` each.
  int liveness_probe_tries = 4;
  int liveness_probe_timeout_ms = 250;  ///< [1, 10000]

  IoStatus validate() const;
};

class GigeCamera final : public Camera {
 public:
  explicit GigeCamera(GigeOptions options);
  ~GigeCamera() override;
  GigeCamera(const GigeCamera&) = delete;
  GigeCamera& operator=(const GigeCamera&) = delete;

  /// Finds the camera and applies the options. Runs Aravis discovery (about 1 s) when the id
  /// is neither an IP address nor already in Aravis' device list. kDisconnected if it is not
  /// found, kUnsupported if it lacks the pixel format or a feature, with Aravis' message.
  IoStatus open();
  /// Releases the camera. Unref of the stream and device still waits for Aravis' GVCP retries
  /// (about 2.5 s each) when the camera vanished or hung.
  void close();

  IoStatus start() override;
  void stop() override;
  IoStatus grab(CameraFrame& frame, std::chrono::milliseconds timeout) override;
  IoStatus trigger() override;
  CameraStats stats() const override;
  const std::string& name() const override { return name_; }

  /// Image size after open() (pixels).
  int width() const { return width_; }
  int height() const { return height_; }
  /// The underlying ArvCamera (nullptr before open()), for vendor features and tests.
  _ArvCamera* native_handle() const { return camera_; }

 private:
  IoStatus configure();
  /// Unpacks a complete buffer on the driver thread; counts what it rejects.
  IoStatus unpack_buffer(_ArvBuffer* buffer, CameraFrame& frame, const HostTime& received);
  static void on_control_lost(void* device, void* self);
  /// Makes the probe of a GigE Vision device after open() (none for other devices or when off).
  void make_probe();
  /// kDisconnected when a probe is due (no frame for the period) and the device does not answer.
  IoStatus probe_if_due();
  /// The next probe one period from now (after a buffer, a probe or the start).
  void probe_later();

  GigeOptions options_;
  IoStatus options_status_;
  std::string name_;
  _ArvCamera* camera_ = nullptr;
  _ArvStream* stream_ = nullptr;
  unsigned long control_lost_handler_ = 0;
  std::atomic<bool> control_lost_{false};
  /// The last control command (software trigger) timed out: the device does not answer GVCP,
  /// so stop() does not send AcquisitionStop (another 5 x 500 ms+ of retries; measured 4.9 s).
  bool control_silent_ = false;
  bool streaming_ = false;
  std::size_t payload_bytes_ = 0;  ///< size of each stream buffer we allocated
  int width_ = 0;
  int height_ = 0;
  FrameIdUnwrapper frame_ids_;
  CameraStats stats_;
  std::unique_ptr<GvcpProbe> probe_;
  std::chrono::steady_clock::time_point next_probe_ = std::chrono::steady_clock::time_point::max();
};

}  // namespace nav::drivers
