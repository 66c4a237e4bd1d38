#pragma once
// The `vision:` section of the navd config (config/README.md "vision"): navd registers its own
// camera frames (daemon/include/nav/daemon/vision/vision_link.h) instead of reading the
// registrations of a dive log (replay) or waiting for an external vision process (live).

#include <optional>
#include <string>

namespace nav::daemon {

struct VisionConfig {
  bool enabled = false;  ///< enabled: true
  int threads = 1;       ///< registration threads, [1, 64]
  /// Features kept per image in the bounded LRU cache, [2, 100000] (about 1 MB per image at
  /// ~2000 SIFT features: docs/performance.md "Vision in the loop").
  int cache_images = 64;
  /// Live mode: proposals waiting for a thread, [1, 100000]; beyond, the oldest expires.
  int queue_capacity = 64;
  /// Replay: data time from a pair's image to when its answer is applied, s, [0, 3600]; must be
  /// below filter.registration_wait_s (else every pair expires).
  double answer_delay_s = 1.0;
  /// Directory of the frames (frame_png_name(frame_id) inside); "" = the dive directory's
  /// images/ (replay) or the camera's image_dir (live).
  std::string image_dir;
  /// Expected frame size, pixels; 0 = not checked. A frame of another size fails its pairs.
  int image_width_px = 0, image_height_px = 0;
  /// Scene-depth prior: depth = altitude of image i, sigma = fraction * depth + floor.
  double depth_sigma_fraction = 0.1;
  double depth_sigma_floor_m = 0.2;
  /// Registrations with an inlier of a larger leverage are refused, (0, 1]; empty: the
  /// registration pipeline's default (nav/vision/registration.h RegistrationOptions).
  std::optional<double> max_leverage;
  /// The registrations' noise model in navd's loop: feature noise (px, [0.001, 10]), the factor of
  /// the fit's residual sigma ([0.1, 10]) and a model error added to every covariance (deg per
  /// angle, [0, 10]). More conservative than the registration pipeline's calibrated defaults
  /// (nav/vision/registration.h): the filter's gate and the closed loop were measured with
  /// these (docs/performance.md "Vision in the loop").
  double pixel_sigma_px = 0.5;
  double residual_sigma_factor = 1.0;
  double model_sigma_deg = 0.2;
  /// Systematic feature displacements (a smooth field over each image) as a fraction of the
  /// noise measured on the pair, [0, 10] (nav/vision/two_view_refinement.h systematic_*).
  double systematic_noise_fraction = 1.0;
  /// Registrations with fewer inliers are refused, and those with an angle of a larger sigma
  /// (deg) unless they have uncertain_min_inliers; empty: the registration pipeline's defaults.
  std::optional<int> min_inliers;
  std::optional<double> max_sigma_deg;
  std::optional<int> uncertain_min_inliers;
  /// The pose-constrained search band's floor, sigma px, [0, 1000] (nav/vision/pccs.h "Floor");
  /// empty: the registration pipeline's default (40 px, for frames of about 1000 px focal
  /// length: scale it with the focal length).
  std::optional<double> band_floor_sigma_px;
};

}  // namespace nav::daemon
