// CameraPlayback: the dive's NAV_IMAGE events through the fake GigE camera; see
// camera_playback.h.
#include "camera_playback.h"

#include <spdlog/spdlog.h>
#include <time.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <variant>

#include "nav/daemon/log/dive_log.h"
#include "nav/daemon/system/host_clock.h"

namespace nav::hil {
namespace {

/// The dive's 16-bit frame, empty if it has none or it cannot be read.
cv::Mat load_frame(const std::filesystem::path& path) {
  cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty() || image.type() != CV_16UC1) return {};
  return image;
}

}  // namespace

CameraPlayback::CameraPlayback(FakeGigeCamera& camera, std::filesystem::path log_path,
                               std::filesystem::path dive_dir, double latency_s,
                               std::vector<PlayerFault> vanish, std::int64_t lead_us)
    : camera_(camera),
      log_path_(std::move(log_path)),
      dive_dir_(std::move(dive_dir)),
      vanish_(std::move(vanish)),
      latency_us_(std::llround(latency_s * 1e6)),
      lead_us_(lead_us) {}

CameraPlayback::~CameraPlayback() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

void CameraPlayback::start(std::int64_t dive_start_us, std::int64_t host_start_us, double speed) {
  if (thread_.joinable()) return;
  dive_start_us_ = dive_start_us;
  host_start_us_ = host_start_us;
  speed_ = speed;
  thread_ = std::thread([this] { run(); });
}

CameraPlayReport CameraPlayback::finish(const std::atomic<bool>& stop) {
  while (thread_.joinable() && !stop.load()) {
    // The thread ends after the last image's frame is sent; poll `stop` meanwhile.
    if (done_.load()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  if (!camera_.running() && report_.reappear_error.empty()) {
    report_.reappear_error = camera_.reappear();  // a window past the last image: end it
  }
  const FakeCameraStats s = camera_.stats();
  CameraPlayReport r = report_;
  r.sent = s.sent;
  r.not_taken = s.not_taken;
  r.max_send_late_s = s.max_late_s;
  r.mean_send_late_s = s.mean_late_s;
  return r;
}

bool CameraPlayback::gone_at(std::int64_t t_us) const {
  const double dive_s = (t_us - host_start_us_) * 1e-6 * speed_;
  return std::any_of(vanish_.begin(), vanish_.end(),
                     [&](const PlayerFault& f) { return f.active(dive_s); });
}

void CameraPlayback::follow_windows() {
  const bool gone = gone_at(daemon::monotonic_us());
  if (gone && camera_.running()) {
    camera_.vanish();
    ++report_.vanishes;
  } else if (!gone && !camera_.running()) {
    const std::string why = camera_.reappear();
    if (!why.empty() && report_.reappear_error.empty()) report_.reappear_error = why;
  }
}

bool CameraPlayback::wait_until(std::int64_t until_us) {
  for (;;) {
    follow_windows();
    std::int64_t next = until_us;  // the nearest window edge before `until_us`
    for (const PlayerFault& f : vanish_) {
      for (const double edge_s : {f.from_s, f.to_s}) {
        const std::int64_t edge = host_start_us_ + std::llround(edge_s * 1e6 / speed_);
        if (edge > daemon::monotonic_us() && edge < next) next = edge;
      }
    }
    if (!daemon::sleep_until_monotonic_us(next, stop_)) return false;
    if (next == until_us) {
      follow_windows();
      return true;
    }
  }
}

void CameraPlayback::run() {
  try {
    daemon::DiveLogReader reader(log_path_.string());
    while (!stop_.load()) {
      std::optional<daemon::DiveLogEvent> event = reader.next();
      if (!event) break;
      const auto* image = std::get_if<navlcm::image_metadata_t>(&*event);
      if (image == nullptr) continue;
      cv::Mat frame;
      if (!image->file_path.empty()) {
        frame = load_frame(dive_dir_ / image->file_path);
        if (frame.empty()) ++report_.frame_missing;
      }
      const double offset_us =
          static_cast<double>(image->time_of_validity_us + latency_us_ - dive_start_us_);
      const std::int64_t due_us = host_start_us_ + std::llround(offset_us / speed_);
      if (!wait_until(due_us - lead_us_)) break;
      ++report_.images;
      if (gone_at(due_us - lead_us_) || gone_at(due_us) || !camera_.running()) {
        ++report_.vanished;  // the camera is gone when this frame is due
        continue;
      }
      if (!frame.empty()) ++report_.with_frame;
      camera_.fire(std::move(frame), due_us);
    }
    // Let the last frame go out (the fake acts on a trigger within ~100 ms of its due time).
    const std::int64_t give_up_us = daemon::monotonic_us() + lead_us_ + 1'000'000;
    while (!stop_.load() && !camera_.idle() && daemon::monotonic_us() < give_up_us)
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
  } catch (const std::exception& e) {
    spdlog::error("hil camera playback: {}", e.what());
  }
  done_.store(true);
}

}  // namespace nav::hil
