// Camera source loop (nav/daemon/sources/camera_source.h).
#include "nav/daemon/sources/camera_source.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <vector>

namespace nav::daemon {
namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kRelaxed = std::memory_order_relaxed;

/// 16-bit image with 12 significant bits (Mono8 scaled by 16).
cv::Mat as_16bit(const cv::Mat& image) {
  if (image.depth() == CV_16U) return image;
  cv::Mat out;
  image.convertTo(out, CV_16U, 16.0);
  return out;
}

void sleep_unless_stopped(std::chrono::milliseconds duration, const std::atomic<bool>& stop) {
  const auto end = Clock::now() + duration;
  while (!stop.load() && Clock::now() < end) {
    std::this_thread::sleep_for(
        std::min<Clock::duration>(end - Clock::now(), std::chrono::milliseconds(20)));
  }
}

class CameraLoop {
 public:
  explicit CameraLoop(CameraContext& c)
      : c_(c),
        latency_us_(std::llround(c.sensor.latency_s * 1e6)),
        image_dir_(c.sensor.camera.image_dir) {
    if (!image_dir_.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(image_dir_, ec);
      if (ec)
        spdlog::error("sensor {}: cannot create {}: {}", c.sensor.name, image_dir_, ec.message());
    }
  }

  void on_frame(const drivers::CameraFrame& frame) {
    SensorHealth& h = c_.health;
    h.messages.fetch_add(1, kRelaxed);
    h.bytes.fetch_add(frame.image.total() * frame.image.elemSize(), kRelaxed);
    h.last_message_monotonic_us.store(frame.time.host.monotonic_us, kRelaxed);
    const std::int64_t validity = camera_validity_us(frame, latency_us_);
    std::string file_path;
    if (!image_dir_.empty()) {
      const std::string name = frame_png_name(frame.frame_id);
      if (write_frame_png(frame, (std::filesystem::path(image_dir_) / name).string())) {
        file_path = "images/" + name;
      } else {
        h.decode_errors.fetch_add(1, kRelaxed);
      }
    }
    ImageEvent e;
    e.time.validity_us = validity;
    e.time.host_monotonic_us = frame.time.host.monotonic_us;
    e.time.host_realtime_us = frame.time.host.realtime_us;
    e.time.sensor_index = c_.sensor_index;
    e.frame_id = frame.frame_id;
    h.measurements.fetch_add(1, kRelaxed);
    if (!c_.producer.push(e)) h.queue_drops.fetch_add(1, kRelaxed);
    if (c_.publisher != nullptr) {
      c_.publisher->publish_image(
          image_metadata(frame, validity, file_path, c_.options.thumbnail_width_px));
    }
  }

  void run(const CameraOpener& open) {
    c_.health.active.store(true);
    std::unique_ptr<drivers::Camera> camera;
    std::chrono::milliseconds backoff{0};
    bool ever_connected = false;
    drivers::CameraFrame frame;
    const bool software = c_.sensor.camera.trigger == Trigger::kSoftware;
    const auto trigger_period = std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(1.0 / c_.sensor.camera.frame_rate_hz));
    auto next_trigger = Clock::now();
    while (!c_.stop.load()) {
      if (!camera) {
        drivers::IoStatus status;
        camera = open(status);
        if (camera) status = camera->start();
        if (!camera || !status.ok()) {
          camera.reset();
          c_.health.open_failures.fetch_add(1, kRelaxed);
          if (backoff.count() == 0) spdlog::warn("sensor {}: {}", c_.sensor.name, status.message());
          backoff = std::clamp(backoff * 2, c_.options.device.reconnect_initial,
                               c_.options.device.reconnect_max);
          sleep_unless_stopped(backoff, c_.stop);
          continue;
        }
        backoff = std::chrono::milliseconds{0};
        if (ever_connected) c_.health.reconnects.fetch_add(1, kRelaxed);
        ever_connected = true;
        c_.health.connected.store(true, kRelaxed);
      }
      if (software && Clock::now() >= next_trigger) {
        (void)camera->trigger();  // a failed trigger shows up as a grab timeout
        next_trigger += trigger_period;
        if (next_trigger < Clock::now()) next_trigger = Clock::now() + trigger_period;
      }
      const drivers::IoStatus status = camera->grab(frame, c_.options.device.read_timeout);
      if (status.ok()) {
        on_frame(frame);
      } else if (status.code() != drivers::IoCode::kTimeout) {
        spdlog::warn("sensor {}: {}", c_.sensor.name, status.message());
        c_.health.connected.store(false, kRelaxed);
        c_.health.disconnects.fetch_add(1, kRelaxed);
        camera->stop();
        camera.reset();
      }
    }
    if (camera) camera->stop();
    c_.health.connected.store(false, kRelaxed);
  }

 private:
  CameraContext& c_;
  std::int64_t latency_us_;
  std::string image_dir_;
};

}  // namespace

std::int64_t camera_validity_us(const drivers::CameraFrame& f, std::int64_t latency_us) {
  const std::int64_t grab_mono = f.time.host.monotonic_us;
  std::int64_t arrival_mono = grab_mono;
  if (f.arrival_realtime_us) {
    arrival_mono = *f.arrival_realtime_us - (f.time.host.realtime_us - grab_mono);
    // A wall clock step between the arrival and the grab moves the conversion by the step:
    // later than the grab is impossible, earlier than kMaxArrivalBeforeGrabUs is not a frame
    // the loop was waiting on. Either way the grab's own monotonic time is the better one.
    if (arrival_mono > grab_mono || arrival_mono < grab_mono - kMaxArrivalBeforeGrabUs) {
      arrival_mono = grab_mono;
    }
  }
  return arrival_mono - latency_us;
}

navlcm::image_metadata_t image_metadata(const drivers::CameraFrame& frame, std::int64_t validity_us,
                                        const std::string& file_path, int thumbnail_width_px) {
  navlcm::image_metadata_t m{};
  m.utime = frame.time.host.realtime_us;
  m.time_of_validity_us = validity_us;
  m.frame_id = static_cast<std::int64_t>(frame.frame_id);
  m.state_id = -1;
  m.file_path = file_path;
  m.width = frame.image.cols;
  m.height = frame.image.rows;
  m.bits_per_pixel = frame.image.depth() == CV_16U ? 16 : 8;
  m.exposure_us = 0.0;
  m.gain_db = 0.0;
  if (frame.image.empty() || thumbnail_width_px <= 0) return m;
  const int w = std::min(thumbnail_width_px, frame.image.cols);
  const int h =
      std::max(1, static_cast<int>(std::lround(double(frame.image.rows) * w / frame.image.cols)));
  cv::Mat small, grey;
  cv::resize(frame.image, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  // 12 significant bits in 16-bit frames -> 8 bits; 8-bit frames as they are.
  small.convertTo(grey, CV_8U, frame.image.depth() == CV_16U ? 1.0 / 16.0 : 1.0);
  m.thumbnail_width = w;
  m.thumbnail_height = h;
  m.thumbnail.assign(grey.datastart, grey.dataend);
  m.thumbnail_num_bytes = static_cast<std::int32_t>(m.thumbnail.size());
  return m;
}

std::string frame_png_name(std::uint64_t frame_id) {
  char name[32];
  std::snprintf(name, sizeof name, "%06llu.png", static_cast<unsigned long long>(frame_id));
  return name;
}

bool write_frame_png(const drivers::CameraFrame& frame, const std::string& path) {
  try {
    if (cv::imwrite(path, as_16bit(frame.image))) return true;
    spdlog::error("cannot write {}", path);
  } catch (const cv::Exception& e) {
    spdlog::error("cannot write {}: {}", path, e.what());
  }
  return false;
}

void run_camera_device(const CameraOpener& open, CameraContext& context) {
  CameraLoop(context).run(open);
}

}  // namespace nav::daemon
