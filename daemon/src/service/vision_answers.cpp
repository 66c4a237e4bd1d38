// Live vision answers on NAV_REGISTRATION (service/vision_answers.h).
#include "nav/daemon/service/vision_answers.h"

#include <lcm/lcm-cpp.hpp>
#include <navlcm/registration_t.hpp>
#include <algorithm>
#include <stdexcept>

#include "nav/daemon/system/host_clock.h"

namespace nav::daemon::service {

VisionAnswerPublisher::VisionAnswerPublisher(const daemon::LcmConfig& config,
                                             std::int64_t run_id)
    : channel_(config.registration.name),
      run_id_(run_id),
      lcm_(std::make_unique<lcm::LCM>(config.url)) {}

VisionAnswerPublisher::~VisionAnswerPublisher() = default;

void VisionAnswerPublisher::publish(const daemon::vision::VisionAnswer& answer) {
  const core::Registration& r = answer.registration;
  navlcm::registration_t msg{};
  msg.utime = daemon::realtime_us();
  msg.frame_id_i = r.frame_id_i;
  msg.frame_id_j = r.frame_id_j;
  msg.success = r.success;
  for (int a = 0; a < 5; ++a) {
    msg.measurement[a] = r.z(a);
    for (int b = 0; b < 5; ++b) msg.covariance[5 * a + b] = r.covariance(a, b);
  }
  msg.overlap_fraction = -1.0;  // unknown on the vehicle
  msg.is_outlier = false;
  msg.run_id = run_id_;
  msg.sequence = static_cast<std::int64_t>(answer.request.sequence);
  const std::lock_guard<std::mutex> lock(mutex_);
  if (!key_.empty()) {
    last_signed_us_ = std::max(daemon::realtime_us(), last_signed_us_ + 1);
    daemon::sign_registration(msg, key_, kSignerId, last_signed_us_);
  }
  if (lcm_->good() && lcm_->publish(channel_, &msg) == 0) {
    ++published_;
  } else {
    ++failures_;
  }
}

std::unique_ptr<daemon::vision::VisionLink> make_live_vision(const daemon::NavdConfig& config,
                                                            VisionAnswerPublisher& answers) {
  if (!config.vision.enabled) return nullptr;
  std::string dir = config.vision.image_dir;
  for (const daemon::SensorConfig& s : config.sensors) {
    if (dir.empty() && daemon::is_camera(s.type)) dir = s.camera.image_dir;
  }
  if (dir.empty()) {
    throw std::invalid_argument(
        "vision.enabled in live mode needs the frames on disk: set vision.image_dir or the "
        "camera's image_dir");
  }
  return std::make_unique<daemon::vision::VisionLink>(
      config, dir, daemon::vision::VisionLink::Mode::kLive,
      [&answers](daemon::vision::VisionAnswer&& a) { answers.publish(a); });
}

}  // namespace nav::daemon::service
