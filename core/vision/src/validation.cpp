// Validation of a refined registration (validation.h).

#include "nav/vision/validation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "median.h"
#include "nav/vision/relative_pose_5dof.h"

namespace nav::vision {
namespace {

using detail::median;

void set_failure(RegistrationResult& result, RegistrationFailure failure,
                 const std::string& reason) {
  result.success = false;
  result.failure = failure;
  result.reason = reason;
}

}  // namespace

double chi2_5_survival(double x) {
  if (!(x > 0.0)) return 1.0;
  return std::erfc(std::sqrt(0.5 * x)) +
         std::sqrt(2.0 * x / std::numbers::pi) * std::exp(-0.5 * x) * (1.0 + x / 3.0);
}

double chi2_5_quantile(double p) {
  if (!(p > 0.0 && p < 1.0)) {
    std::ostringstream msg;
    msg << "chi2_5_quantile: probability must be in (0, 1), got " << p;
    throw std::invalid_argument(msg.str());
  }
  double lo = 0.0, hi = 1000.0;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (1.0 - chi2_5_survival(mid) < p)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}

std::string failure_name(RegistrationFailure failure) {
  switch (failure) {
    case RegistrationFailure::kOk:
      return "ok";
    case RegistrationFailure::kBadImage:
      return "bad image";
    case RegistrationFailure::kTooFewFeatures:
      return "too few features";
    case RegistrationFailure::kTooFewMatches:
      return "too few matches";
    case RegistrationFailure::kEssentialFailed:
      return "essential matrix failed";
    case RegistrationFailure::kTooFewInliers:
      return "too few inliers";
    case RegistrationFailure::kRefinementFailed:
      return "refinement failed";
    case RegistrationFailure::kReprojectionError:
      return "reprojection error";
    case RegistrationFailure::kDepthOutOfPrior:
      return "depth out of prior";
    case RegistrationFailure::kTooUncertain:
      return "too uncertain";
  }
  return "unknown failure " + std::to_string(static_cast<int>(failure));
}

void validate_registration(const TwoViewRefinement& refinement, const RelativePosePrior* prior,
                           const ValidationOptions& options, RegistrationResult& result) {
  result.success = true;
  result.failure = RegistrationFailure::kOk;
  result.reason.clear();
  result.z = refinement.z;
  result.covariance = refinement.covariance;
  result.inliers = static_cast<int>(refinement.used_matches.size());
  result.reprojection_rms_px = refinement.reprojection_rms_px;
  result.noise_sigma_px = refinement.robust_sigma_px;
  result.prior_chi2 = -1.0;
  result.max_leverage = refinement.max_leverage;
  std::ostringstream why;

  // 1-5: the refinement itself.
  if (!refinement.converged) {
    const RegistrationFailure f = refinement.failure == RegistrationFailure::kOk
                                      ? RegistrationFailure::kRefinementFailed
                                      : refinement.failure;
    set_failure(result, f, refinement.reason);
    return;
  }
  if (result.inliers < options.min_inliers) {
    why << result.inliers << " inliers after refinement, fewer than the " << options.min_inliers
        << " required";
    set_failure(result, RegistrationFailure::kTooFewInliers, why.str());
    return;
  }
  if (!(refinement.inlier_area_fraction >= options.min_inlier_area_fraction)) {
    why << result.inliers << " inliers spread over " << refinement.inlier_area_fraction
        << " of the frame (second-moment area), less than the " << options.min_inlier_area_fraction
        << " required";
    set_failure(result, RegistrationFailure::kTooFewInliers, why.str());
    return;
  }
  if (!(refinement.max_leverage <= options.max_leverage)) {
    why << "one of the " << result.inliers << " inliers decides a direction of the pose alone: "
        << "leverage " << refinement.max_leverage << " above " << options.max_leverage;
    set_failure(result, RegistrationFailure::kTooFewInliers, why.str());
    return;
  }
  Eigen::Index widest = 0;
  const double widest_sigma = refinement.covariance.diagonal().cwiseSqrt().maxCoeff(&widest);
  if (!(widest_sigma <= options.max_sigma_rad) && result.inliers < options.uncertain_min_inliers) {
    constexpr std::array<const char*, 5> kAngles = {"azimuth", "elevation", "roll", "pitch",
                                                    "heading"};
    constexpr double kDeg = 180.0 / std::numbers::pi;
    why << "the " << kAngles[static_cast<std::size_t>(widest)] << " sigma " << widest_sigma * kDeg
        << " deg is above the " << options.max_sigma_rad * kDeg
        << " deg a measurement of fewer than " << options.uncertain_min_inliers
        << " inliers may have (" << result.inliers << " inliers)";
    set_failure(result, RegistrationFailure::kTooUncertain, why.str());
    return;
  }
  if (!(refinement.reprojection_rms_px <= options.max_reprojection_rms_px)) {
    why << "reprojection RMS " << refinement.reprojection_rms_px << " px above the limit "
        << options.max_reprojection_rms_px << " px";
    set_failure(result, RegistrationFailure::kReprojectionError, why.str());
    return;
  }
  const auto behind = [](const std::vector<double>& d) {
    return std::count_if(d.begin(), d.end(), [](double v) { return !(v > 0.0); });
  };
  const long behind_i = behind(refinement.depths_i), behind_j = behind(refinement.depths_j);
  if (behind_i + behind_j > 0 || refinement.depths_i.empty()) {
    why << "after refinement " << behind_i << " points are behind camera i and " << behind_j
        << " behind camera j (of " << refinement.depths_i.size() << ")";
    set_failure(result, RegistrationFailure::kRefinementFailed, why.str());
    return;
  }
  if (prior == nullptr) return;

  // 6: depths against the scene-depth prior, in metres via the prior's baseline length.
  const Eigen::Vector3d t = prior->x_i_j.head<3>();
  const double baseline_m = t.norm();
  PredictedZ predicted;
  try {
    predicted = predict_z(*prior);
  } catch (const std::domain_error& e) {
    set_failure(result, RegistrationFailure::kRefinementFailed,
                std::string("prior unusable for validation: ") + e.what());
    return;
  }
  const Eigen::Vector3d u = t / baseline_m;
  const double baseline_var = u.dot(prior->covariance.topLeftCorner<3, 3>() * u);
  const double depth_var = prior->scene_depth_sigma_m * prior->scene_depth_sigma_m;
  const auto outside = [&](double d_units) {
    const double d_m = d_units * baseline_m;
    const double sigma = std::sqrt(depth_var + d_units * d_units * baseline_var);
    return std::abs(d_m - prior->scene_depth_m) > options.depth_k_sigma * sigma;
  };
  const double median_units = median(refinement.depths_i);
  const long n_out = std::count_if(refinement.depths_i.begin(), refinement.depths_i.end(), outside);
  const double fraction_out =
      static_cast<double>(n_out) / static_cast<double>(refinement.depths_i.size());
  if (outside(median_units) || fraction_out > options.max_fraction_depth_outliers) {
    why << "triangulated depths disagree with the scene-depth prior " << prior->scene_depth_m
        << " +- " << prior->scene_depth_sigma_m << " m: median " << median_units * baseline_m
        << " m (baseline " << baseline_m << " m), " << n_out << " of " << refinement.depths_i.size()
        << " points beyond " << options.depth_k_sigma << " sigma (at most "
        << options.max_fraction_depth_outliers << " allowed)";
    set_failure(result, RegistrationFailure::kDepthOutOfPrior, why.str());
    return;
  }

  // 7: chi2 of z against the prior's prediction, reported, gated on request.
  try {
    result.prior_chi2 = z_chi2(refinement.z, refinement.covariance, predicted);
  } catch (const std::invalid_argument& e) {
    set_failure(result, RegistrationFailure::kRefinementFailed, e.what());
    return;
  }
  if (options.gate_prior_chi2) {
    const double gate = chi2_5_quantile(options.prior_chi2_confidence);
    if (result.prior_chi2 > gate) {
      why << "z disagrees with the prior: chi2(5) = " << result.prior_chi2 << " above " << gate
          << " (confidence " << options.prior_chi2_confidence << ")";
      set_failure(result, RegistrationFailure::kRefinementFailed, why.str());
    }
  }
}

}  // namespace nav::vision
