#include "nav/sim/oracle.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"

namespace nav::sim {
namespace {

constexpr double kPi = std::numbers::pi;

double uniform(std::mt19937_64& rng, double a, double b) {
  return std::uniform_real_distribution<double>(a, b)(rng);
}

}  // namespace

std::string OracleOptions::validate() const {
  for (double s : {azimuth_sigma_rad, elevation_sigma_rad, rotation_sigma_rad})
    if (!(s > 0.0 && s < 1.0)) return "*_sigma_rad: outside (0, 1) rad";
  if (!(outlier_rate >= 0.0 && outlier_rate <= 1.0)) return "outlier_rate: outside [0, 1]";
  if (!(min_overlap >= 0.0 && min_overlap <= 1.0)) return "min_overlap: outside [0, 1]";
  if (!(overlap_zero >= 0.0 && overlap_zero < overlap_full && overlap_full <= 1.0))
    return "overlap_zero/overlap_full: need 0 <= zero < full <= 1";
  if (!(max_success_probability >= 0.0 && max_success_probability <= 1.0))
    return "max_success_probability: outside [0, 1]";
  if (!(time_gap_scale_s > 0.0)) return "time_gap_scale_s: must be > 0";
  return "";
}

CameraGeometry CameraGeometry::from_config(const daemon::SensorConfig& s) {
  CameraGeometry c;
  c.fx_px = s.camera.fx_px;
  c.fy_px = s.camera.fy_px;
  c.cx_px = s.camera.cx_px;
  c.cy_px = s.camera.cy_px;
  c.x_body_camera << s.mount.lever_arm_m[0], s.mount.lever_arm_m[1], s.mount.lever_arm_m[2],
      s.mount.rpy_rad[0], s.mount.rpy_rad[1], s.mount.rpy_rad[2];
  return c;
}

Polygon2 image_footprint(const CameraGeometry& cam, const core::Vec12& x, double floor_depth_m) {
  const core::Vec6 x_world_camera = core::head_to_tail(x.head<6>(), cam.x_body_camera);
  const core::Mat3 R = core::rotation_from_euler(x_world_camera.tail<3>());
  const core::Vec3 p = x_world_camera.head<3>();
  const double w = 2.0 * cam.cx_px, h = 2.0 * cam.cy_px;
  Polygon2 poly;
  for (const auto& [u, v] : {std::pair{0.0, 0.0}, {w, 0.0}, {w, h}, {0.0, h}}) {
    const core::Vec3 d =
        R * core::Vec3((u - cam.cx_px) / cam.fx_px, (v - cam.cy_px) / cam.fy_px, 1.0);
    if (d.z() < 0.05 || floor_depth_m <= p.z()) return {};
    const double t = (floor_depth_m - p.z()) / d.z();
    poly.push_back({p.x() + t * d.x(), p.y() + t * d.y()});
  }
  return poly;
}

double RegistrationOracle::overlap_fraction(const Polygon2& a, const Polygon2& b) {
  const double smaller = std::min(area_m2(a), area_m2(b));
  if (smaller <= 0.0) return 0.0;
  return area_m2(intersect_convex(a, b)) / smaller;
}

RegistrationOracle::RegistrationOracle(const CameraGeometry& camera, const OracleOptions& options,
                                       std::uint64_t seed)
    : camera_(camera), options_(options), rng_(seed) {
  model_.x_body_camera = camera.x_body_camera;
  const double s[5] = {options.azimuth_sigma_rad, options.elevation_sigma_rad,
                       options.rotation_sigma_rad, options.rotation_sigma_rad,
                       options.rotation_sigma_rad};
  for (int i = 0; i < 5; ++i) {
    covariance_(i, i) = s[i] * s[i];
    covariance_sqrt_(i, i) = s[i];
  }
}

std::vector<navlcm::registration_t> RegistrationOracle::add_image(const OracleImage& image) {
  std::vector<navlcm::registration_t> out;
  Stored j{image, {}, 0.0};
  for (const Point2& q : image.footprint) {
    j.centre.x_m += q.x_m / image.footprint.size();
    j.centre.y_m += q.y_m / image.footprint.size();
  }
  for (const Point2& q : image.footprint)
    j.radius_m = std::max(j.radius_m, std::hypot(q.x_m - j.centre.x_m, q.y_m - j.centre.y_m));
  if (!image.footprint.empty()) {
    for (const Stored& i : images_) {
      const double d = std::hypot(i.centre.x_m - j.centre.x_m, i.centre.y_m - j.centre.y_m);
      if (d >= i.radius_m + j.radius_m) continue;
      const double overlap = overlap_fraction(i.image.footprint, image.footprint);
      if (overlap < options_.min_overlap) continue;
      if (auto r = try_pair(i, image, overlap)) out.push_back(*r);
    }
  }
  images_.push_back(std::move(j));
  return out;
}

std::optional<navlcm::registration_t> RegistrationOracle::try_pair(const Stored& i,
                                                                   const OracleImage& j,
                                                                   double overlap) {
  const core::Vec12& xi = i.image.x_true;
  const core::Vec12& xj = j.x_true;
  if (model_.baseline_is_degenerate(xi, xj)) {
    ++counts_.degenerate_skipped;
    return std::nullopt;
  }
  navlcm::registration_t r{};
  r.frame_id_i = i.image.frame_id;
  r.frame_id_j = j.frame_id;
  r.overlap_fraction = overlap;
  const double o = std::clamp(
      (overlap - options_.overlap_zero) / (options_.overlap_full - options_.overlap_zero), 0.0,
      1.0);
  const double gap_s = (j.t_us - i.image.t_us) * 1e-6;
  const double p_success = options_.max_success_probability * o *
                           (0.3 + 0.7 * std::exp(-gap_s / options_.time_gap_scale_s));
  // Always draw the same numbers per pair so that options change only what they govern.
  const double u_success = uniform(rng_, 0.0, 1.0), u_outlier = uniform(rng_, 0.0, 1.0);
  Vec5 n;
  for (int k = 0; k < 5; ++k) n[k] = std::normal_distribution<double>(0.0, 1.0)(rng_);
  const double flip = uniform(rng_, -kPi / 3.0, kPi / 3.0);
  const double elevation = uniform(rng_, -0.6, 0.6);
  const double heading_error = uniform(rng_, 5.0, 20.0) * kPi / 180.0 * (flip >= 0 ? 1.0 : -1.0);

  r.success = u_success < p_success;
  ++counts_.registrations;
  for (int a = 0; a < 5; ++a)
    for (int b = 0; b < 5; ++b) r.covariance[a * 5 + b] = covariance_(a, b);
  if (!r.success) return r;
  ++counts_.succeeded;
  Vec5 z = model_.predict(xi, xj) + covariance_sqrt_ * n;
  r.is_outlier = u_outlier < options_.outlier_rate;
  if (r.is_outlier) {
    ++counts_.outliers;
    z[0] += kPi + flip;  // the baseline points the wrong way
    z[1] = elevation;
    z[4] += heading_error;
  }
  z[0] = core::wrap_angle(z[0]);
  z[1] = std::clamp(z[1], -kPi / 2.0, kPi / 2.0);
  for (int k = 2; k < 5; ++k) z[k] = core::wrap_angle(z[k]);
  for (int k = 0; k < 5; ++k) r.measurement[k] = z[k];
  return r;
}

}  // namespace nav::sim
