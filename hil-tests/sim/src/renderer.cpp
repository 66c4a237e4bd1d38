#include "nav/sim/renderer.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <limits>
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

double Renderer::albedo(double x_m, double y_m, double relief_m, double footprint_m) const {
  // Sediment grain (2 cm), pebbles (6 cm), ripples and patches (15 cm, 0.5 m, 1.2 m): texture
  // at every scale from a few pixels to the footprint; relief tops (debris, rust) are brighter,
  // as on the wreck. Each octave is faded to its mean where its lattice spacing L approaches
  // the pixel's footprint p (weight smoothstep(L / p - 1) : full at L >= 2p, none at L <= p):
  // frequency clamping (Ebert et al., "Texturing and Modeling", 3rd ed., ch. 2), the box
  // filter of the pixel's area that a camera applies and a point sample does not; without it
  // the 2 cm octave aliases beyond ~8 m range into a moire that moves unlike the seafloor.
  struct Octave {
    double lattice_m, weight;
    std::uint64_t seed;
  };
  static constexpr Octave kOctaves[] = {
      {0.02, 0.1, 1}, {0.06, 0.1, 4}, {0.15, 0.16, 2}, {0.5, 0.12, 5}, {1.2, 0.2, 3}};
  double a = 0.35 + 0.2 * std::clamp(relief_m / 3.0, 0.0, 1.0);
  for (const Octave& o : kOctaves) {
    const double keep =
        footprint_m > 0.0 ? smooth(std::clamp(o.lattice_m / footprint_m - 1.0, 0.0, 1.0)) : 1.0;
    if (keep > 0.0) {
      const double noise = value_noise(x_m / o.lattice_m, y_m / o.lattice_m, seed_ + o.seed);
      a += keep * o.weight * (noise - 0.5);
    }
  }
  return std::clamp(a, 0.05, 1.0);
}

double Renderer::albedo(const core::Vec3& q_m, const core::Vec3& normal, double relief_m,
                        double footprint_m) const {
  // Triplanar mapping (Geiss, GPU Gems 3, ch. 1.5): the planar texture projected along each
  // axis, blended by the normal's components to the 4th power. A floor or a deck (normal
  // vertical) has the planar texture of albedo(x, y) exactly; a wall gets its own texture in
  // its plane instead of the floor's smeared down it in vertical streaks. Each projection gets
  // its own offset so the wall's texture is not the floor's rotated.
  const core::Vec3 w = normal.cwiseAbs().array().pow(4.0).matrix();
  struct Projection {
    double weight, u_m, v_m;
  };
  const Projection projections[] = {{w.z(), q_m.x(), q_m.y()},
                                    {w.x(), q_m.y() + 517.0, q_m.z()},
                                    {w.y(), q_m.x() - 733.0, q_m.z()}};
  // A projection of less than 5 % of the weights is skipped (slopes under ~25 deg: the planar
  // texture alone, one noise evaluation per pixel over rough relief; a level floor: exactly
  // albedo(x, y)).
  constexpr double kNegligible = 0.05;
  double a = 0.0, kept = 0.0;
  for (const Projection& p : projections) {
    if (p.weight <= kNegligible * w.sum()) continue;
    a += p.weight * albedo(p.u_m, p.v_m, relief_m, footprint_m);
    kept += p.weight;
  }
  return a / kept;
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

Renderer::TopMap Renderer::top_map(const core::Vec3& p_cam) const {
  // 1 m cells over a 30 m square around the camera (its rays leave it only > 15 m / tan(half
  // diagonal field) ~ 18 m below the camera, far below any relief), each holding the shallowest
  // grid sample of itself and its 8 neighbours: anywhere within 1 m of a point of the cell the
  // seafloor is at least that deep. Outside the square: the shallowest of the whole square.
  TopMap m;
  m.x0_m = std::floor(p_cam.x()) - 15.0;
  m.y0_m = std::floor(p_cam.y()) - 15.0;
  const double step = seafloor_->options().resolution_m;
  const int per_cell = std::max(1, static_cast<int>(std::lround(1.0 / step)));
  std::vector<double> own(static_cast<std::size_t>(TopMap::kCells * TopMap::kCells), 1e12);
  for (int cy = 0; cy < TopMap::kCells; ++cy)
    for (int cx = 0; cx < TopMap::kCells; ++cx) {
      double& top = own[static_cast<std::size_t>(cy * TopMap::kCells + cx)];
      for (int iy = 0; iy <= per_cell; ++iy)
        for (int ix = 0; ix <= per_cell; ++ix)
          top = std::min(top, seafloor_->depth_m(m.x0_m + cx + ix * step, m.y0_m + cy + iy * step));
    }
  m.depth_m.assign(own.size(), 1e12);
  m.overall_m = 1e12;
  for (int cy = 0; cy < TopMap::kCells; ++cy)
    for (int cx = 0; cx < TopMap::kCells; ++cx) {
      double top = 1e12;
      for (int ny = std::max(0, cy - 1); ny <= std::min(TopMap::kCells - 1, cy + 1); ++ny)
        for (int nx = std::max(0, cx - 1); nx <= std::min(TopMap::kCells - 1, cx + 1); ++nx)
          top = std::min(top, own[static_cast<std::size_t>(ny * TopMap::kCells + nx)]);
      m.depth_m[static_cast<std::size_t>(cy * TopMap::kCells + cx)] = top;
      m.overall_m = std::min(m.overall_m, top);
    }
  return m;
}

double Renderer::TopMap::at(double x_m, double y_m) const {
  const int cx = static_cast<int>(std::floor(x_m - x0_m)), cy = static_cast<int>(std::floor(y_m - y0_m));
  if (cx < 0 || cy < 0 || cx >= kCells || cy >= kCells) return overall_m;
  return depth_m[static_cast<std::size_t>(cy * kCells + cx)];
}

double Renderer::first_hit(const core::Vec3& p, const core::Vec3& d, const TopMap& top) const {
  // First crossing of the ray p + t d (d.z > 0) below the height field. Each step is the larger
  // of two safe ones: down to the ray point's cell bound (TopMap) or 1 m sideways, whichever
  // comes first (inside the bound's 1 m margin); at most half a grid cell sideways and half the
  // height above the floor below (at least 5 cm) down. It stops at the first point below the
  // surface and bisects the last step. The hull's and deckhouses' near-vertical walls (slopes up to
  // ~25 on the 0.1 m grid) are hit where the ray meets them and nothing behind them shows
  // through (a fixed-point iteration on the depth diverges there: it alternated between deck
  // and mud and painted one surface's texture at the other's depth, an image of no 3-D scene).
  const double half_cell = 0.5 * seafloor_->options().resolution_m;
  const double sideways = std::hypot(d.x(), d.y());
  const auto height_above = [&](double t) {
    const core::Vec3 q = p + t * d;
    return seafloor_->depth_m(q.x(), q.y()) - q.z();
  };
  const auto bound_step = [&](double t) {  // safe step above the cell bound, else 0
    const core::Vec3 q = p + t * d;
    const double clear_m = top.at(q.x(), q.y()) - q.z();
    if (clear_m <= 0.05) return 0.0;
    return sideways > 0.0 ? std::min(clear_m / d.z(), 1.0 / sideways) : clear_m / d.z();
  };
  double t0 = 0.05, g0 = height_above(t0);
  if (g0 <= 0.0) return t0;
  for (int k = 0; k < 100000; ++k) {
    double dt = std::max(0.05, 0.5 * g0) / d.z();
    if (sideways > 0.0) dt = std::min(dt, half_cell / sideways);
    dt = std::max(dt, bound_step(t0));
    const double t1 = t0 + dt, g1 = height_above(t1);
    if (g1 <= 0.0) {
      double lo = t0, hi = t1;  // above at lo, below at hi
      for (int b = 0; b < 14; ++b) {
        const double mid = 0.5 * (lo + hi);
        (height_above(mid) > 0.0 ? lo : hi) = mid;
      }
      return 0.5 * (lo + hi);
    }
    t0 = t1;
    g0 = g1;
  }
  return t0;
}

core::Vec3 Renderer::surface_point(const core::Vec3& p_world, const core::Vec3& d_world) const {
  return p_world + first_hit(p_world, d_world, top_map(p_world)) * d_world;
}

std::vector<core::Vec3> Renderer::surface_points(const core::Vec3& p_world,
                                                 const std::vector<core::Vec3>& d_world) const {
  const TopMap top = top_map(p_world);
  std::vector<core::Vec3> out;
  out.reserve(d_world.size());
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  for (const core::Vec3& d : d_world)  // a ray near or above the horizon meets nothing
    out.push_back(d.z() > 0.05 ? core::Vec3(p_world + first_hit(p_world, d, top) * d)
                               : core::Vec3(kNaN, kNaN, kNaN));
  return out;
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
  const TopMap top = top_map(p_cam);
  // Radiance per unit exposure: the strobe-lit floor plus the backscatter veil.
  cv::Mat radiance = backscatter(p_cam, R, p_strobe, nadir_m, 1.0);
  for (int v = 0; v < h; ++v) {
    auto* row = radiance.ptr<float>(v);
    for (int u = 0; u < w; ++u) {
      // Pixel u's centre is at u (the pinhole model's convention: u = fx X / Z + cx).
      const core::Vec3 ray_cam((u - camera_.cx_px) / camera_.fx_px,
                               (v - camera_.cy_px) / camera_.fy_px, 1.0);
      const core::Vec3 d = R * ray_cam;
      if (d.z() <= 0.05) continue;
      const double t = first_hit(p_cam, d, top);
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
      // The pixel's footprint on the surface: range / focal length, stretched by the incidence.
      const double footprint_m =
          r_cam / (camera_.fx_px * std::max(0.2, std::abs(n.dot(d)) / d.norm()));
      const double cos2 = cos_axis * cos_axis;
      const double a = albedo(q, n, seafloor_->relief_height_m(q.x(), q.y()), footprint_m);
      row[u] += static_cast<float>(a *
                                   lambert /
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
