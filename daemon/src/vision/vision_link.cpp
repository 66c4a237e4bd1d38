// NavFilter <-> VisionWorker on the filter thread (vision/vision_link.h).
#include "nav/daemon/vision/vision_link.h"

#include <spdlog/spdlog.h>

#include <filesystem>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <utility>

#include "nav/daemon/sources/camera_source.h"
#include "nav/daemon/vision/camera_prior.h"
#include "nav/vision/camera_model.h"
#include "nav/vision/two_view_refinement.h"

namespace nav::daemon::vision {

nav::vision::CameraIntrinsics vision_camera(const CameraConfig& camera,
                                            const VisionConfig& vision) {
  nav::vision::CameraIntrinsics c;
  c.fx_px = camera.fx_px;
  c.fy_px = camera.fy_px;
  c.cx_px = camera.cx_px;
  c.cy_px = camera.cy_px;
  const std::vector<double>& d = camera.distortion;
  if (d.size() > 5) {
    throw std::invalid_argument("vision: camera distortion with " + std::to_string(d.size()) +
                                " coefficients; the registration takes k1 k2 p1 p2 [k3]");
  }
  double* k[5] = {&c.k1, &c.k2, &c.p1, &c.p2, &c.k3};
  for (std::size_t i = 0; i < d.size(); ++i) *k[i] = d[i];
  c.width_px = vision.image_width_px;
  c.height_px = vision.image_height_px;
  return c;
}

void enable_vision_in_replay(NavdConfig& config) {
  config.vision.enabled = true;
  if (config.filter.registration_wait_s <= config.vision.answer_delay_s) {
    config.filter.registration_wait_s = kReplayVisionWaitS;
  }
}

int bits_per_pixel(PixelFormat format) {
  switch (format) {
    case PixelFormat::kMono12:
      return 12;
    case PixelFormat::kMono16:
      return 16;
    default:
      return 8;
  }
}

cv::Mat load_frame(const std::string& dir, std::uint64_t frame_id) {
  const std::string path = (std::filesystem::path(dir) / frame_png_name(frame_id)).string();
  cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    throw std::runtime_error("cannot read " + path + " (missing, truncated or not an image)");
  }
  return image;
}

namespace {

const SensorConfig& camera_sensor(const NavdConfig& config) {
  for (const SensorConfig& s : config.sensors) {
    if (is_camera(s.type)) return s;
  }
  throw std::invalid_argument("vision: the config has no camera sensor");
}

}  // namespace

VisionLink::VisionLink(const NavdConfig& config, std::string image_dir, Mode mode,
                       VisionWorker::AnswerSink live_sink)
    : config_(config.vision),
      mode_(mode),
      answer_delay_us_(static_cast<std::int64_t>(config.vision.answer_delay_s * 1e6)),
      live_sink_(std::move(live_sink)) {
  const SensorConfig& camera = camera_sensor(config);
  x_body_camera_ << camera.mount.lever_arm_m[0], camera.mount.lever_arm_m[1],
      camera.mount.lever_arm_m[2], camera.mount.rpy_rad[0], camera.mount.rpy_rad[1],
      camera.mount.rpy_rad[2];
  const nav::vision::CameraIntrinsics intrinsics = vision_camera(camera.camera, config_);
  if (const core::Status s = nav::vision::validate(intrinsics); !s.ok()) {
    throw std::invalid_argument("vision: camera " + camera.name + ": " + s.message());
  }
  nav::vision::RegistrationOptions options;
  options.preprocess.bits_per_pixel = bits_per_pixel(camera.camera.pixel_format);
  if (config_.max_leverage) options.validation.max_leverage = *config_.max_leverage;
  constexpr double kRad = std::numbers::pi / 180.0;
  nav::vision::set_pixel_sigma_keeping_parallax_floor(options.refinement, config_.pixel_sigma_px);
  options.refinement.residual_sigma_factor = config_.residual_sigma_factor;
  options.refinement.model_sigma_rad = config_.model_sigma_deg * kRad;
  options.refinement.systematic_noise_fraction = config_.systematic_noise_fraction;
  if (config_.min_inliers) options.validation.min_inliers = *config_.min_inliers;
  if (config_.max_sigma_deg) options.validation.max_sigma_rad = *config_.max_sigma_deg * kRad;
  if (config_.band_floor_sigma_px) options.pccs.band_floor_sigma_px = *config_.band_floor_sigma_px;
  if (config_.uncertain_min_inliers)
    options.validation.uncertain_min_inliers = *config_.uncertain_min_inliers;
  registration_ = std::make_unique<nav::vision::Registration>(intrinsics, options);
  cache_ = std::make_unique<FeatureCache>(static_cast<std::size_t>(config_.cache_images));
  VisionWorkerOptions w;
  w.threads = config_.threads;
  w.queue_capacity = static_cast<std::size_t>(config_.queue_capacity);
  w.overflow = mode == Mode::kReplay ? Overflow::kBlock : Overflow::kExpireOldest;
  worker_ = std::make_unique<VisionWorker>(
      *registration_, [dir = std::move(image_dir)](std::uint64_t id) { return load_frame(dir, id); },
      *cache_, [this](VisionAnswer&& a) { on_answer(std::move(a)); }, w);
}

VisionLink::~VisionLink() { worker_->stop(); }

void VisionLink::after_measurement(const core::NavFilter& filter) {
  if (filter.last_pending_sequence() == last_sequence_) return;
  for (const core::PendingRegistration& p : filter.pending_registrations()) {
    if (p.sequence <= last_sequence_) continue;
    VisionRequest request;
    request.sequence = p.sequence;
    request.frame_i = p.frame_i;
    request.frame_j = p.frame_j;
    std::string why;
    request.prior = pair_prior_from_filter(filter, p, x_body_camera_, config_, &why);
    if (!request.prior) {
      {
        const std::lock_guard<std::mutex> lock(mutex_);
        ++without_prior_;
      }
      spdlog::warn("vision: {}; registering without a pose prior", why);
    }
    if (mode_ == Mode::kReplay) {
      const std::lock_guard<std::mutex> lock(mutex_);
      outstanding_[p.sequence].due_realtime_us = p.asked_realtime_us + answer_delay_us_;
    } else {
      request.deadline_realtime_us = p.deadline_realtime_us;
    }
    worker_->submit(std::move(request));
  }
  last_sequence_ = filter.last_pending_sequence();
}

void VisionLink::on_answer(VisionAnswer&& answer) {
  if (mode_ == Mode::kLive) {
    if (live_sink_) live_sink_(std::move(answer));
    return;
  }
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    auto it = outstanding_.find(answer.request.sequence);
    if (it == outstanding_.end()) return;  // not asked through this link
    it->second.answer = std::move(answer);
  }
  answered_.notify_all();
}

void VisionLink::before_measurement(std::int64_t host_realtime_us,
                                    core::RegistrationTable& table) {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!outstanding_.empty() && outstanding_.begin()->second.due_realtime_us <= host_realtime_us) {
    answered_.wait(lock, [&] { return outstanding_.begin()->second.answer.has_value(); });
    Outstanding done = std::move(outstanding_.begin()->second);
    outstanding_.erase(outstanding_.begin());
    core::Registration reg = done.answer->registration;
    reg.available_us = done.due_realtime_us;
    applied_.push_back(
        AppliedAnswer{reg, done.answer->reason, done.answer->inliers, done.answer->max_leverage});
    try {
      table.insert(reg);
    } catch (const std::invalid_argument& e) {
      ++refused_;
      spdlog::warn("vision: answer for {}-{} refused: {}", reg.frame_id_i, reg.frame_id_j,
                   e.what());
    }
  }
}

VisionLinkStats VisionLink::stats() const {
  VisionLinkStats s;
  s.worker = worker_->counters();
  s.cache = cache_->counters();
  const std::lock_guard<std::mutex> lock(mutex_);
  s.without_prior = without_prior_;
  s.refused = refused_;
  return s;
}

}  // namespace nav::daemon::vision
