// GigE Vision / GenICam camera on Aravis 0.8 (see gige_camera.h): configuration through the
// ArvCamera convenience API (SFNC feature names), buffer pool streaming without a stream
// callback, and unpacking on the driver thread.

#include "nav/drivers/transports/gige_camera.h"

#include <arv.h>

#include <algorithm>
#include <system_error>

#include "gvcp_probe.h"

namespace nav::drivers {
namespace {

/// Converts and clears a GError into an IoStatus; Ok when there is none.
IoStatus take_error(GError*& error, const std::string& device, const std::string& what,
                    IoCode code = IoCode::kUnsupported) {
  if (error == nullptr) return IoStatus::Ok();
  IoStatus s = IoStatus::Error(code, device, what + ": " + error->message);
  g_clear_error(&error);
  return s;
}

/// True when `id` is an IPv4 address (opened directly) or already in Aravis' device list.
bool is_known_device(const std::string& id) {
  if (!id.empty() && g_hostname_is_ip_address(id.c_str())) return true;
  const unsigned n = arv_get_n_devices();
  if (id.empty()) return n > 0;
  for (unsigned i = 0; i < n; ++i) {
    const char* known = arv_get_device_id(i);
    if (known != nullptr && id == known) return true;
  }
  return false;
}

}  // namespace

IoStatus GigeOptions::validate() const {
  const std::string dev = camera_id.empty() ? "gige" : camera_id;
  auto bad = [&](const std::string& what) {
    return IoStatus::Error(IoCode::kInvalidArgument, dev, what);
  };
  if (!(exposure_us > 0.0) || exposure_us > 1e8)
    return bad("options.exposure_us must be in (0, 1e8]");
  if (gain && !(*gain >= 0.0 && *gain < 1e6)) return bad("options.gain must be finite and >= 0");
  if (!(frame_rate_hz >= 0.0 && frame_rate_hz < 1e6))
    return bad("options.frame_rate_hz must be >= 0");
  if (offset_x < 0 || offset_y < 0 || width < 0 || height < 0 || (width == 0) != (height == 0)) {
    return bad("options region: offsets >= 0, width and height both 0 or both > 0");
  }
  if (packet_size_bytes != 0 && (packet_size_bytes < 576 || packet_size_bytes > 65535)) {
    return bad("options.packet_size_bytes must be 0 (auto) or 576..65535");
  }
  if (buffer_count < 2 || buffer_count > 256) return bad("options.buffer_count must be in 2..256");
  if (frame_id_bits != 16 && frame_id_bits != 64)
    return bad("options.frame_id_bits must be 16 or 64");
  if (liveness_probe_period_ms < 0 || liveness_probe_period_ms > 60000)
    return bad("options.liveness_probe_period_ms must be in [0, 60000]");
  if (liveness_probe_tries < 1 || liveness_probe_tries > 100)
    return bad("options.liveness_probe_tries must be in [1, 100]");
  if (liveness_probe_timeout_ms < 1 || liveness_probe_timeout_ms > 10000)
    return bad("options.liveness_probe_timeout_ms must be in [1, 10000]");
  if (trigger_mode == TriggerMode::kHardware && trigger_source.empty()) {
    return bad("options.trigger_source is empty for hardware trigger");
  }
  return IoStatus::Ok();
}

GigeCamera::GigeCamera(GigeOptions options)
    : options_(std::move(options)),
      options_status_(options_.validate()),
      name_(options_.camera_id.empty() ? "gige" : options_.camera_id),
      frame_ids_(options_.frame_id_bits, options_.frame_id_bits == 16) {}

GigeCamera::~GigeCamera() { close(); }

void GigeCamera::on_control_lost(void* /*device*/, void* self) {
  // Runs on an Aravis thread: only raise the flag; grab() reports it.
  static_cast<GigeCamera*>(self)->control_lost_.store(true);
}

IoStatus GigeCamera::open() {
  if (!options_status_.ok()) return options_status_;
  close();
  GError* error = nullptr;
  if (!is_known_device(options_.camera_id)) {
    // Discovery on every interface (about 1 s), so the device is opened through the interface
    // it answered on; a stale or empty list can bind the stream to the wrong local address.
    arv_update_device_list();
  }
  camera_ =
      arv_camera_new(options_.camera_id.empty() ? nullptr : options_.camera_id.c_str(), &error);
  if (camera_ == nullptr)
    return take_error(error, name_, "camera not found", IoCode::kDisconnected);
  control_lost_.store(false);
  control_silent_ = false;
  control_lost_handler_ = g_signal_connect(arv_camera_get_device(camera_), "control-lost",
                                           G_CALLBACK(&GigeCamera::on_control_lost), this);
  IoStatus s = configure();
  if (!s.ok()) {
    close();
    return s;
  }
  make_probe();
  return s;
}

void GigeCamera::make_probe() {
  probe_.reset();
  if (options_.liveness_probe_period_ms == 0 || !arv_camera_is_gv_device(camera_)) return;
  auto* gv = ARV_GV_DEVICE(arv_camera_get_device(camera_));
  GSocketAddress* address = arv_gv_device_get_device_address(gv);  // owned by the device
  sockaddr_in device{};
  if (address == nullptr || g_socket_address_get_family(address) != G_SOCKET_FAMILY_IPV4 ||
      !g_socket_address_to_native(address, &device, sizeof device, nullptr)) {
    return;  // not an IPv4 GVCP peer: the heartbeat alone watches it
  }
  try {
    probe_ = std::make_unique<GvcpProbe>(
        device, std::chrono::milliseconds(options_.liveness_probe_timeout_ms),
        options_.liveness_probe_tries);
  } catch (const std::system_error&) {
    // No socket for it (descriptors exhausted): the heartbeat alone watches the camera.
  }
}

void GigeCamera::probe_later() {
  next_probe_ = std::chrono::steady_clock::now() +
                std::chrono::milliseconds(options_.liveness_probe_period_ms);
}

IoStatus GigeCamera::probe_if_due() {
  const auto now = std::chrono::steady_clock::now();
  if (probe_ == nullptr || now < next_probe_) return IoStatus::Ok();
  std::string why;
  if (!probe_->answers(&why)) {
    control_silent_ = true;  // stop() must not wait out Aravis' retries on AcquisitionStop
    return IoStatus::Error(IoCode::kDisconnected, name_, "camera does not answer: " + why);
  }
  probe_later();
  return IoStatus::Ok();
}

IoStatus GigeCamera::configure() {
  GError* error = nullptr;
  const uint32_t want = pfnc_code(options_.pixel_format);
  arv_camera_set_pixel_format(camera_, want, &error);
  IoStatus s =
      take_error(error, name_, std::string("pixel format ") + genicam_name(options_.pixel_format));
  if (s.ok() && arv_camera_get_pixel_format(camera_, nullptr) != want) {
    s = IoStatus::Error(
        IoCode::kUnsupported, name_,
        std::string("camera did not accept ") + genicam_name(options_.pixel_format));
  }
  if (!s.ok()) return s;
  arv_camera_set_acquisition_mode(camera_, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
  if (s = take_error(error, name_, "AcquisitionMode Continuous"); !s.ok()) return s;
  arv_camera_set_exposure_time(camera_, options_.exposure_us, &error);
  if (s = take_error(error, name_, "exposure time"); !s.ok()) return s;
  if (options_.gain) {
    arv_camera_set_gain(camera_, *options_.gain, &error);
    if (s = take_error(error, name_, "gain"); !s.ok()) return s;
  }
  switch (options_.trigger_mode) {
    case TriggerMode::kFreeRun:
      arv_camera_clear_triggers(camera_, &error);
      if (error == nullptr && options_.frame_rate_hz > 0.0) {
        arv_camera_set_frame_rate(camera_, options_.frame_rate_hz, &error);
      }
      break;
    case TriggerMode::kSoftware:
      arv_camera_set_trigger(camera_, "Software", &error);
      break;
    case TriggerMode::kHardware:
      arv_camera_set_trigger(camera_, options_.trigger_source.c_str(), &error);
      break;
  }
  if (s = take_error(error, name_, "trigger / frame rate"); !s.ok()) return s;
  if (options_.width > 0) {
    arv_camera_set_region(camera_, options_.offset_x, options_.offset_y, options_.width,
                          options_.height, &error);
    if (s = take_error(error, name_, "region of interest"); !s.ok()) return s;
  }
  if (arv_camera_is_gv_device(camera_)) {
    if (options_.packet_size_bytes > 0) {
      arv_camera_gv_set_packet_size(camera_, options_.packet_size_bytes, &error);
      if (s = take_error(error, name_, "packet size"); !s.ok()) return s;
    } else {
      // Largest packet the path supports; on failure the 1500-byte default still works.
      arv_camera_gv_auto_packet_size(camera_, &error);
      g_clear_error(&error);
    }
  }
  gint x = 0, y = 0, w = 0, h = 0;
  arv_camera_get_region(camera_, &x, &y, &w, &h, &error);
  if (s = take_error(error, name_, "region"); !s.ok()) return s;
  width_ = w;
  height_ = h;
  return IoStatus::Ok();
}

void GigeCamera::close() {
  stop();
  if (camera_ != nullptr) {
    if (control_lost_handler_ != 0)
      g_signal_handler_disconnect(arv_camera_get_device(camera_), control_lost_handler_);
    control_lost_handler_ = 0;
    g_clear_object(&camera_);
  }
  probe_.reset();
}

IoStatus GigeCamera::start() {
  if (camera_ == nullptr)
    return IoStatus::Error(IoCode::kDisconnected, name_, "start: camera not open");
  if (streaming_) return IoStatus::Ok();
  GError* error = nullptr;
  const guint payload = arv_camera_get_payload(camera_, &error);
  if (IoStatus s = take_error(error, name_, "payload size", IoCode::kSystemError); !s.ok())
    return s;
  stream_ = arv_camera_create_stream(camera_, nullptr, nullptr, &error);  // no callback: see header
  if (stream_ == nullptr) return take_error(error, name_, "create stream", IoCode::kSystemError);
  payload_bytes_ = payload;
  for (int i = 0; i < options_.buffer_count; ++i)
    arv_stream_push_buffer(stream_, arv_buffer_new(payload, nullptr));
  arv_camera_start_acquisition(camera_, &error);
  if (IoStatus s = take_error(error, name_, "start acquisition", IoCode::kSystemError); !s.ok()) {
    g_clear_object(&stream_);
    return s;
  }
  frame_ids_.reset();
  streaming_ = true;
  probe_later();
  return IoStatus::Ok();
}

void GigeCamera::stop() {
  if (!streaming_) return;
  streaming_ = false;
  if (!control_lost_.load() && !control_silent_) {
    GError* error = nullptr;
    arv_camera_stop_acquisition(camera_, &error);  // may fail if the camera is gone: nothing to do
    g_clear_error(&error);
  }  // else a vanished or hung device: the command would only wait out its retries
  if (stream_ != nullptr) {
    guint64 completed = 0, failures = 0, underruns = 0;
    arv_stream_get_statistics(stream_, &completed, &failures, &underruns);
    stats_.underruns += underruns;  // keep the totals of the stream we are about to drop
  }
  g_clear_object(&stream_);  // stops the stream thread and frees the buffers
}

IoStatus GigeCamera::trigger() {
  if (camera_ == nullptr)
    return IoStatus::Error(IoCode::kDisconnected, name_, "trigger: camera not open");
  if (options_.trigger_mode != TriggerMode::kSoftware) {
    return IoStatus::Error(IoCode::kInvalidArgument, name_,
                           "trigger: camera is not in software trigger mode");
  }
  GError* error = nullptr;
  arv_camera_software_trigger(camera_, &error);
  control_silent_ =
      error != nullptr && g_error_matches(error, ARV_DEVICE_ERROR, ARV_DEVICE_ERROR_TIMEOUT);
  return take_error(error, name_, "software trigger",
                    control_silent_ ? IoCode::kTimeout : IoCode::kSystemError);
}

CameraStats GigeCamera::stats() const {
  CameraStats s = stats_;
  if (stream_ != nullptr) {
    guint64 completed = 0, failures = 0, underruns = 0;
    arv_stream_get_statistics(stream_, &completed, &failures, &underruns);
    s.underruns += underruns;
  }
  return s;
}

IoStatus GigeCamera::grab(CameraFrame& frame, std::chrono::milliseconds timeout) {
  if (!streaming_)
    return IoStatus::Error(IoCode::kInvalidArgument, name_, "grab: not streaming (call start)");
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    if (control_lost_.load())
      return IoStatus::Error(IoCode::kDisconnected, name_, "control lost (heartbeat)");
    if (IoStatus s = probe_if_due(); !s.ok()) return s;
    const auto now = std::chrono::steady_clock::now();
    const auto wake = probe_ != nullptr ? std::min(deadline, next_probe_) : deadline;
    const auto left = std::chrono::duration_cast<std::chrono::microseconds>(wake - now);
    ArvBuffer* buffer = arv_stream_timeout_pop_buffer(
        stream_, static_cast<guint64>(std::max<int64_t>(0, left.count())));
    if (buffer == nullptr) {
      if (std::chrono::steady_clock::now() >= deadline)
        return IoStatus::Error(IoCode::kTimeout, name_, "grab: no frame within timeout");
      continue;  // a probe is due before the deadline
    }
    const HostTime received = host_time_now();
    IoStatus s = IoStatus::Ok();
    if (arv_buffer_get_status(buffer) != ARV_BUFFER_STATUS_SUCCESS) {
      ++stats_.incomplete;
      s = IoStatus::Error(IoCode::kTimeout, name_, "incomplete buffer");
    } else {
      s = unpack_buffer(buffer, frame, received);
    }
    arv_stream_push_buffer(stream_, buffer);  // back to the pool before anything else
    probe_later();  // any buffer, complete or not, shows the device is there
    if (s.ok()) return s;
    // Incomplete or malformed buffers are counted and skipped; wait for the next one.
  }
}

IoStatus GigeCamera::unpack_buffer(_ArvBuffer* buffer, CameraFrame& frame,
                                   const HostTime& received) {
  const auto format = pixel_format_from_pfnc(arv_buffer_get_image_pixel_format(buffer));
  const ArvBufferPayloadType type = arv_buffer_get_payload_type(buffer);
  if (!format || (type != ARV_BUFFER_PAYLOAD_TYPE_IMAGE &&
                  type != ARV_BUFFER_PAYLOAD_TYPE_EXTENDED_CHUNK_DATA)) {
    ++stats_.unpack_errors;
    return IoStatus::Error(IoCode::kInvalidArgument, name_, "buffer is not a Mono image");
  }
  gint x_padding = 0, y_padding = 0;
  arv_buffer_get_image_padding(buffer, &x_padding, &y_padding);
  const ImageLayout layout{arv_buffer_get_image_width(buffer), arv_buffer_get_image_height(buffer),
                           *format, static_cast<std::size_t>(std::max(0, x_padding))};
  size_t size = 0;
  const auto* data = static_cast<const uint8_t*>(arv_buffer_get_image_data(buffer, &size));
  if (data != nullptr && size == 0) {
    // Aravis 0.8's in-process fake reports no received size: bound by the buffer we allocated.
    size_t ignored = 0;
    const auto* base = static_cast<const uint8_t*>(arv_buffer_get_data(buffer, &ignored));
    if (base != nullptr && data >= base && data <= base + payload_bytes_) {
      size = payload_bytes_ - static_cast<size_t>(data - base);
    }
  }
  if (data == nullptr) size = 0;
  if (IoStatus s = unpack_mono({data, size}, layout, frame.image); !s.ok()) {
    ++stats_.unpack_errors;
    return s;
  }
  frame.format = *format;
  frame.raw_frame_id = arv_buffer_get_frame_id(buffer);
  const FrameIdUnwrapper::Update id = frame_ids_.update(frame.raw_frame_id);
  frame.frame_id = id.id;
  frame.lost_before = id.lost;
  stats_.lost += id.lost;
  if (id.restarted) ++stats_.restarts;
  const guint64 device_ns = arv_buffer_get_timestamp(buffer);
  const guint64 system_ns = arv_buffer_get_system_timestamp(buffer);
  frame.time.host = received;
  frame.time.sensor_time_us = device_ns != 0
                                  ? std::optional<int64_t>(static_cast<int64_t>(device_ns / 1000))
                                  : std::nullopt;
  // Aravis stamps with the kernel's CLOCK_REALTIME: moved onto host_time_now()'s (timestamps.h).
  frame.arrival_realtime_us =
      system_ns != 0
          ? std::optional<int64_t>(static_cast<int64_t>(system_ns / 1000) + realtime_offset_us())
          : std::nullopt;
  ++stats_.frames;
  return IoStatus::Ok();
}

}  // namespace nav::drivers
