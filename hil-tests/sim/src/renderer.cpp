#include "nav/sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"
#include "nav/sim/sensor_streams.h"

namespace nav::sim {
namespace {

double hash_unit(std::int64_t ix, std::int64_t iy, std::uint64_t seed) {
  std::uint64_t h = derive_seed(seed ^ (static_cast<std::uint64_t>(ix) * 0x9E3779B97F4A7C15ULL),
                                static_cast<std::uint64_t>(iy));
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);
}

double smooth(double t) { return t * t * (3.0 - 2.0 * t); }

}  // namespace

Renderer::Renderer(const CameraGeometry& camera, const Seafloor& seafloor,
                   const RenderOptions& options, std::uint64_t seed)
    : camera_(camera), seafloor_(&seafloor), options_(options), seed_(seed) {}

double Renderer::value_noise(double x, double y, std::uint64_t s) const {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const double ax = smooth(x - fx), ay = smooth(y - fy);
  const double a = hash_unit(ix, iy, s), b = hash_unit(ix + 1, iy, s);
  const double c = hash_unit(ix, iy + 1, s), d = hash_unit(ix + 1, iy + 1, s);
  return (1 - ay) * ((1 - ax) * a + ax * b) + ay * ((1 - ax) * c + ax * d);
}

double Renderer::albedo(double x_m, double y_m, double relief_m) const {
  // Sediment grain (2 cm), pebbles (6 cm), ripples and patches (15 cm, 0.5 m, 1.2 m): texture
  // at every scale from a few pixels to the footprint; relief tops (debris, rust) are brighter,
  // as on the wreck.
  const double fine = value_noise(x_m / 0.02, y_m / 0.02, seed_ + 1);
  const double pebble = value_noise(x_m / 0.06, y_m / 0.06, seed_ + 4);
  const double mid = value_noise(x_m / 0.15, y_m / 0.15, seed_ + 2);
  const double patch = value_noise(x_m / 0.5, y_m / 0.5, seed_ + 5);
  const double coarse = value_noise(x_m / 1.2, y_m / 1.2, seed_ + 3);
  const double relief = std::clamp(relief_m / 3.0, 0.0, 1.0);
  const double a = 0.35 + 0.1 * (fine - 0.5) + 0.1 * (pebble - 0.5) + 0.16 * (mid - 0.5) +
                   0.12 * (patch - 0.5) + 0.2 * (coarse - 0.5) + 0.2 * relief;
  return std::clamp(a, 0.05, 1.0);
}

cv::Mat Renderer::backscatter(const core::Vec3& p_cam, const core::Mat3& R_world_cam,
                              const core::Vec3& p_strobe, double range_m, double exposure) const {
  // Single scattering along each ray (isotropic phase function, Jaffe 1990): the light the
  // water between the camera and the floor scatters back into the pixel,
  //   B(ray) = beta * sum_k exp(-c (s_k + r_k)) / r_k^2 ds,  r_k = |p(s_k) - strobe|,
  // integrated over s in [0.3 m, range_m] with 12 samples. It varies smoothly over the image,
  // so it is evaluated on a grid every kStep pixels and interpolated.
  constexpr int kStep = 16, kSamples = 12;
  const int w = camera_.width_px(), h = camera_.height_px();
  cv::Mat coarse(h / kStep + 2, w / kStep + 2, CV_32F);
  const double c = options_.attenuation_per_m;
  for (int gv = 0; gv < coarse.rows; ++gv) {
    for (int gu = 0; gu < coarse.cols; ++gu) {
      const core::Vec3 ray_cam((gu * kStep - camera_.cx_px) / camera_.fx_px,
                               (gv * kStep - camera_.cy_px) / camera_.fy_px, 1.0);
      const core::Vec3 d = R_world_cam * ray_cam.normalized();
      const double s0 = 0.3, ds = std::max(0.0, range_m - s0) / kSamples;
      double sum = 0.0;
      for (int k = 0; k < kSamples; ++k) {
        const double s = s0 + (k + 0.5) * ds;
        const double r2 = (p_cam + s * d - p_strobe).squaredNorm();
        sum += std::exp(-c * (s + std::sqrt(r2))) / r2 * ds;
      }
      coarse.at<float>(gv, gu) =
          static_cast<float>(options_.backscatter_per_m_sr * 0.35 * sum * exposure);
    }
  }
  cv::Mat full;
  cv::resize(coarse, full, cv::Size(coarse.cols * kStep, coarse.rows * kStep), 0, 0,
             cv::INTER_LINEAR);
  return full(cv::Rect(0, 0, w, h)).clone();
}

cv::Mat Renderer::render(const core::Vec12& x, std::uint64_t frame_seed, double* gain_db) const {
  const core::Vec6 x_wc = core::head_to_tail(x.head<6>(), camera_.x_body_camera);
  const core::Mat3 R = core::rotation_from_euler(x_wc.tail<3>());
  const core::Vec3 p_cam = x_wc.head<3>();
  const core::Vec3 p_strobe = p_cam + R * options_.strobe_in_camera_m;
  const int w = camera_.width_px(), h = camera_.height_px();
  std::mt19937_64 rng(derive_seed(seed_, frame_seed));
  std::normal_distribution<double> normal(0.0, 1.0);
  const double floor0 = seafloor_->depth_m(p_cam.x(), p_cam.y());
  const double e = 0.05;  // m, central differences for the surface normal
  auto irradiance = [&](double range_m) {
    return 0.35 / (range_m * range_m) * std::exp(-options_.attenuation_per_m * 2.0 * range_m);
  };
  const double nadir_m = std::max(0.3, floor0 - p_cam.z());
  // Radiance per unit exposure: the strobe-lit floor plus the backscatter veil.
  cv::Mat radiance = backscatter(p_cam, R, p_strobe, nadir_m, 1.0);
  for (int v = 0; v < h; ++v) {
    auto* row = radiance.ptr<float>(v);
    for (int u = 0; u < w; ++u) {
      const core::Vec3 ray_cam((u + 0.5 - camera_.cx_px) / camera_.fx_px,
                               (v + 0.5 - camera_.cy_px) / camera_.fy_px, 1.0);
      const core::Vec3 d = R * ray_cam;
      if (d.z() <= 0.05) continue;
      // The ray meets the surface z = depth(x, y): fixed point from the plane below the camera.
      double t = (floor0 - p_cam.z()) / d.z();
      for (int k = 0; k < 4; ++k) {
        const core::Vec3 q = p_cam + t * d;
        t = std::max(0.05, (seafloor_->depth_m(q.x(), q.y()) - p_cam.z()) / d.z());
      }
      const core::Vec3 q = p_cam + t * d;
      const double dzdx =
          (seafloor_->depth_m(q.x() + e, q.y()) - seafloor_->depth_m(q.x() - e, q.y())) / (2 * e);
      const double dzdy =
          (seafloor_->depth_m(q.x(), q.y() + e) - seafloor_->depth_m(q.x(), q.y() - e)) / (2 * e);
      const core::Vec3 n = core::Vec3(dzdx, dzdy, -1.0).normalized();  // up, out of the floor
      const core::Vec3 to_strobe = p_strobe - q;
      const double r_strobe = to_strobe.norm(), r_cam = t * d.norm();
      const double lambert = std::max(0.0, n.dot(to_strobe) / r_strobe);
      const double cos_axis = 1.0 / ray_cam.norm();
      const double cos2 = cos_axis * cos_axis;
      row[u] += static_cast<float>(albedo(q.x(), q.y(), floor0 - q.z()) * lambert /
                                   (r_strobe * r_strobe) *
                                   std::exp(-options_.attenuation_per_m * (r_strobe + r_cam)) *
                                   cos2 * cos2);
    }
  }
  // Auto exposure metered on the central half of the frame: its mean gives target_counts (a
  // floor far below, or a hull top close to the camera, neither saturates nor goes black).
  const double metered = cv::mean(radiance(cv::Rect(w / 4, h / 4, w / 2, h / 2)))[0];
  const double exposure = options_.target_counts / std::max(metered, 1e-12);
  if (gain_db) *gain_db = 20.0 * std::log10(exposure * irradiance(1.0) / options_.target_counts);
  cv::Mat frame(h, w, CV_16UC1);
  for (int v = 0; v < h; ++v) {
    auto* row = frame.ptr<std::uint16_t>(v);
    const float* in = radiance.ptr<float>(v);
    for (int u = 0; u < w; ++u) {
      const double signal = in[u] * exposure;
      const double shot = std::sqrt(std::max(0.0, signal) * options_.counts_per_electron);
      const double value =
          signal + shot * normal(rng) + options_.read_noise_counts * normal(rng) + 40.0;
      row[u] = static_cast<std::uint16_t>(std::clamp(std::lround(value), 0L, 4095L));
    }
  }
  return frame;
}

cv::Mat Renderer::thumbnail(const cv::Mat& frame) const {
  const int w = std::min(options_.thumbnail_width_px, frame.cols);
  const int h = std::max(1, static_cast<int>(std::lround(double(frame.rows) * w / frame.cols)));
  cv::Mat small, grey;
  cv::resize(frame, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  small.convertTo(grey, CV_8U, 1.0 / 16.0);  // 12 significant bits -> 8
  return grey;
}

}  // namespace nav::sim
