#include "nav/vision/registration.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <vector>

#include "nav/vision/camera_model.h"

namespace nav::vision {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

RegistrationResult failed(RegistrationResult r, RegistrationFailure failure, std::string reason) {
  r.success = false;
  r.failure = failure;
  r.reason = std::move(reason);
  return r;
}

/// The inliers whose parallax after removing the rotation, |x_i - pi(R x_j)| in pixels at the
/// mean focal length, is at least min_px, and whose triangulated depths are positive and below
/// the depth at which min_px of parallax would be reached.
std::vector<int> with_parallax(const ImageFeatures& i, const ImageFeatures& j,
                               const PutativeMatches& matches, const EssentialEstimate& e,
                               const CameraIntrinsics& camera, double min_px) {
  // Depth (baselines) at which min_px of parallax is reached at the mean focal length.
  const double max_depth = 0.5 * (camera.fx_px + camera.fy_px) / std::max(min_px, 1e-3);
  std::vector<int> kept;
  const double focal = 0.5 * (camera.fx_px + camera.fy_px);
  for (int k : e.inliers) {
    const Match& m = matches.matches[static_cast<std::size_t>(k)];
    const Eigen::Vector2d x_i = normalised_from_pixel(camera, i.points_px[static_cast<std::size_t>(m.index_i)]);
    const Eigen::Vector2d x_j = normalised_from_pixel(camera, j.points_px[static_cast<std::size_t>(m.index_j)]);
    const Eigen::Vector3d r = e.R_i_j * Eigen::Vector3d(x_j.x(), x_j.y(), 1.0);
    if (r.z() <= 0.0) continue;
    if ((x_i - r.head<2>() / r.z()).norm() * focal < min_px) continue;
    // The parallax must also lie along the epipolar direction: a finite depth in front of both
    // cameras (a displacement across the epipolar line triangulates near infinity).
    double depth_i = 0.0, depth_j = 0.0;
    if (!triangulate_depths(e.R_i_j, e.t_i_j_unit, x_i, x_j, &depth_i, &depth_j)) continue;
    if (depth_i <= 0.0 || depth_j <= 0.0 || depth_i > max_depth || depth_j > max_depth) continue;
    kept.push_back(k);
  }
  return kept;
}

}  // namespace

Registration::Registration(const CameraIntrinsics& camera, const RegistrationOptions& options)
    : camera_(camera), options_(options), preprocessor_(camera, options.preprocess) {}

core::Status Registration::try_features(const cv::Mat& image, ImageFeatures* out,
                                        const IlluminationMean* mean) const {
  if (core::Status s = validate(camera_); !s.ok()) return s;
  cv::Mat grey;
  if (core::Status s = preprocessor_.run(image, &grey, mean); !s.ok()) return s;
  const bool ideal = options_.preprocess.undistort || !has_distortion(camera_);
  return extract_features(grey, camera_, ideal, options_.features, out);
}

core::Status Registration::try_preprocess(const cv::Mat& image, cv::Mat* out_8u,
                                          const IlluminationMean* mean) const {
  if (core::Status s = validate(camera_); !s.ok()) return s;
  return preprocessor_.run(image, out_8u, mean);
}

ImageFeatures Registration::features(const cv::Mat& image) const {
  ImageFeatures out;
  if (core::Status s = try_features(image, &out); !s.ok()) {
    throw std::invalid_argument("Registration::features: " + s.message());
  }
  return out;
}

RegistrationResult Registration::register_pair(const ImageFeatures& i, const ImageFeatures& j,
                                               const RelativePosePrior* prior) const {
  return register_pair(i, j, prior, nullptr);
}

RegistrationResult Registration::register_pair(const ImageFeatures& i, const ImageFeatures& j,
                                               const RelativePosePrior* prior,
                                               RegistrationDiagnostics* diagnostics) const {
  RegistrationDiagnostics local;
  RegistrationDiagnostics& d = diagnostics != nullptr ? *diagnostics : local;
  d = RegistrationDiagnostics{};
  const auto start = Clock::now();
  RegistrationResult result;
  auto finish = [&](RegistrationResult r) {
    d.timings.total_ms = ms_since(start);
    return r;
  };

  if (core::Status s = validate(camera_); !s.ok()) {
    return finish(failed(result, RegistrationFailure::kBadImage, s.message()));
  }
  const int min_features = options_.min_features;
  if (static_cast<int>(i.size()) < min_features || static_cast<int>(j.size()) < min_features) {
    return finish(failed(result, RegistrationFailure::kTooFewFeatures,
                         "image i has " + std::to_string(i.size()) + " features, image j " +
                             std::to_string(j.size()) + "; at least " +
                             std::to_string(min_features) + " needed in each"));
  }

  auto t0 = Clock::now();
  if (prior != nullptr) {
    try {
      d.matches = match_pose_constrained(i, j, camera_, *prior, options_.pccs);
    } catch (const std::invalid_argument& e) {
      d.timings.matching_ms = ms_since(t0);
      return finish(failed(result, RegistrationFailure::kTooFewMatches,
                           std::string("pose-constrained search: ") + e.what()));
    }
  } else {
    d.matches = match_unconstrained(i, j, options_.matching);
  }
  d.timings.matching_ms = ms_since(t0);
  result.putative_matches = static_cast<int>(d.matches.matches.size());
  result.descriptor_comparisons = d.matches.descriptor_comparisons;
  if (result.putative_matches < options_.essential.min_matches) {
    return finish(failed(result, RegistrationFailure::kTooFewMatches,
                         std::to_string(result.putative_matches) +
                             " putative matches (no overlap?), at least " +
                             std::to_string(options_.essential.min_matches) + " needed"));
  }

  t0 = Clock::now();
  d.essential = estimate_essential(i, j, d.matches, camera_, options_.essential, prior);
  d.timings.essential_ms = ms_since(t0);
  if (!d.essential.ok) {
    return finish(failed(result, RegistrationFailure::kEssentialFailed, d.essential.reason));
  }
  result.inliers = static_cast<int>(d.essential.inliers.size());
  if (result.inliers < options_.min_inliers ||
      result.inliers < options_.min_inlier_fraction * result.putative_matches) {
    return finish(failed(result, RegistrationFailure::kTooFewInliers,
                         std::to_string(result.inliers) + " essential-matrix inliers of " +
                             std::to_string(result.putative_matches) +
                             " putative matches; at least " + std::to_string(options_.min_inliers) +
                             " and a fraction " + std::to_string(options_.min_inlier_fraction) +
                             " needed"));
  }

  t0 = Clock::now();
  EssentialEstimate for_refinement = d.essential;
  for_refinement.inliers = with_parallax(i, j, d.matches, d.essential, camera_,
                                         options_.min_point_parallax_px);
  d.refinement = refine_two_view(i, j, d.matches, for_refinement, camera_, options_.refinement);
  d.timings.refinement_ms = ms_since(t0);

  t0 = Clock::now();
  validate_registration(d.refinement, prior, options_.validation, result);
  d.timings.validation_ms = ms_since(t0);
  if (!result.success && result.reason.empty()) {
    result.reason = failure_name(result.failure);
  }
  return finish(result);
}

}  // namespace nav::vision
