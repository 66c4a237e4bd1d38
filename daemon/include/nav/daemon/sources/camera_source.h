#pragma once
// Camera source: the driver thread of a GigE (Aravis) or V4L2 camera (drivers/transports/
// camera.h). Each frame becomes an ImageEvent in the MeasurementQueue, a navlcm::
// image_metadata_t on NAV_IMAGE (with an 8-bit thumbnail) and, when an image directory is
// configured (camera.image_dir), a 16-bit PNG `<image_dir>/<frame_id %06d>.png` holding the
// 12 significant bits (Mono8 frames are scaled by 16); image_metadata_t.file_path is then
// `images/<frame_id %06d>.png`, relative to the dive directory whose images/ folder image_dir is
// (hil-tests/README.md "A dive directory").
//
// Time of validity: the back end's arrival time stamp (CLOCK_REALTIME, moved onto
// CLOCK_MONOTONIC with the offset sampled at grab) when it has one and it is at most
// kMaxArrivalBeforeGrabUs before the grab and not after it (else a wall clock step fell between
// them), else the grab's host monotonic time, minus the sensor's latency_ms (exposure mid-time
// to arrival).
// Software trigger: with camera.trigger = software the loop triggers at frame_rate_hz.
// Reconnection: a grab error other than a timeout closes the camera; the opener is called again
// with backoff (DeviceLoopOptions), counted as in device_source.h.

#include <functional>
#include <memory>
#include <string>

#include "nav/daemon/sources/device_source.h"
#include "nav/drivers/transports/camera.h"

namespace nav::daemon {

/// Opens and starts nothing else: returns a camera ready for start(), or null with `status`.
using CameraOpener = std::function<std::unique_ptr<drivers::Camera>(drivers::IoStatus& status)>;

struct CameraLoopOptions {
  DeviceLoopOptions device;  ///< read_timeout bounds each grab
  int thumbnail_width_px = 160;
};

struct CameraContext {
  const SensorConfig& sensor;
  std::uint16_t sensor_index = 0;
  MeasurementQueue::Producer& producer;
  LcmRawPublisher* publisher = nullptr;  ///< NAV_IMAGE; null: not published
  SensorHealth& health;
  const std::atomic<bool>& stop;
  CameraLoopOptions options;
};

void run_camera_device(const CameraOpener& open, CameraContext& context);

/// Longest a frame's arrival stamp may precede its grab (camera_validity_us): the loop grabs
/// as frames arrive, so 1 s is generous and far below a wall clock step worth noticing.
inline constexpr std::int64_t kMaxArrivalBeforeGrabUs = 1'000'000;

/// The frame's time of validity on CLOCK_MONOTONIC (file comment), µs.
std::int64_t camera_validity_us(const drivers::CameraFrame& frame, std::int64_t latency_us);

/// The image_metadata_t of a frame (thumbnail included); `file_path` as given.
navlcm::image_metadata_t image_metadata(const drivers::CameraFrame& frame, std::int64_t validity_us,
                                        const std::string& file_path, int thumbnail_width_px);

/// "<frame_id %06d>.png".
std::string frame_png_name(std::uint64_t frame_id);

/// Writes `frame` as a 16-bit PNG (see file comment); false with a logged reason on failure.
bool write_frame_png(const drivers::CameraFrame& frame, const std::string& path);

}  // namespace nav::daemon
