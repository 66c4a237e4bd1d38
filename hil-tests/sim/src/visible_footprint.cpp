#include "nav/sim/visible_footprint.h"

#include <algorithm>
#include <cmath>

#include "nav/core/geometry/rotation.h"

namespace nav::sim {

VisibleFootprint visible_footprint(const Renderer& renderer, const CameraGeometry& camera,
                                   const core::Vec6& x_world_camera,
                                   const VisibleFootprintOptions& options) {
  VisibleFootprint f;
  f.x_world_camera = x_world_camera;
  f.cols = camera.width_px() / options.step_px + 1;
  f.rows = camera.height_px() / options.step_px + 1;
  const core::Mat3 R = core::rotation_from_euler(x_world_camera.tail<3>());
  const core::Vec3 p = x_world_camera.head<3>();
  std::vector<core::Vec3> rays_world;
  for (int r = 0; r < f.rows; ++r)
    for (int c = 0; c < f.cols; ++c)
      rays_world.push_back(R * core::Vec3((c * options.step_px - camera.cx_px) / camera.fx_px,
                                          (r * options.step_px - camera.cy_px) / camera.fy_px,
                                          1.0));
  f.points_world = renderer.surface_points(p, rays_world);
  for (const core::Vec3& q : f.points_world) f.depth_m.push_back((R.transpose() * (q - p)).z());
  f.strobe_world = p + R * renderer.options().strobe_in_camera_m;
  f.attenuation_per_m = renderer.options().attenuation_per_m;
  double sum = 0.0;
  int count = 0;
  for (int r = f.rows / 4; r < f.rows - f.rows / 4; ++r)
    for (int c = f.cols / 4; c < f.cols - f.cols / 4; ++c, ++count) {
      const double rho =
          relative_return(f, f.points_world[static_cast<std::size_t>(r * f.cols + c)]);
      if (std::isfinite(rho)) sum += rho;
    }
  f.metered_return = count > 0 ? sum / count : 0.0;
  return f;
}

double relative_return(const VisibleFootprint& f, const core::Vec3& q_world) {
  const double r_s = (q_world - f.strobe_world).norm();
  const double r_c = (q_world - f.x_world_camera.head<3>()).norm();
  return std::exp(-f.attenuation_per_m * (r_s + r_c)) / std::max(r_s * r_s, 1e-6);
}

bool in_footprint(const VisibleFootprint& f, const core::Vec3& q_world,
                  const VisibleFootprintOptions& options) {
  // Comparisons with NaN (a ray that met nothing) are false.
  return (q_world - f.x_world_camera.head<3>()).norm() <= options.max_range_m &&
         relative_return(f, q_world) >= options.min_relative_return * f.metered_return;
}

double seen_fraction(const VisibleFootprint& a, const VisibleFootprint& b,
                     const CameraGeometry& camera, const VisibleFootprintOptions& options) {
  const core::Mat3 R_b = core::rotation_from_euler(b.x_world_camera.tail<3>());
  const core::Vec3 p_b = b.x_world_camera.head<3>();
  int seen = 0, footprint = 0;
  for (const core::Vec3& q : a.points_world) {
    if (!in_footprint(a, q, options)) continue;
    ++footprint;
    if (!in_footprint(b, q, options)) continue;
    const core::Vec3 x = R_b.transpose() * (q - p_b);
    if (x.z() <= 0.0) continue;
    const double u = camera.fx_px * x.x() / x.z() + camera.cx_px;
    const double v = camera.fy_px * x.y() / x.z() + camera.cy_px;
    if (u < 0.0 || v < 0.0 || u > camera.width_px() - 1 || v > camera.height_px() - 1) continue;
    // b's depth at the nearest cast pixel: the point is hidden if b's ray ends before it.
    const int c = std::clamp(static_cast<int>(std::lround(u / options.step_px)), 0, b.cols - 1);
    const int r = std::clamp(static_cast<int>(std::lround(v / options.step_px)), 0, b.rows - 1);
    const double surface = b.depth_m[static_cast<std::size_t>(r * b.cols + c)];
    const double tolerance =
        std::max(options.occlusion_tolerance_m, options.occlusion_tolerance_fraction * x.z());
    if (x.z() <= surface + tolerance) ++seen;
  }
  const int whole = options.of_image ? static_cast<int>(a.points_world.size()) : footprint;
  return whole > 0 ? static_cast<double>(seen) / whole : 0.0;
}

double visible_overlap(const VisibleFootprint& a, const VisibleFootprint& b,
                       const CameraGeometry& camera, const VisibleFootprintOptions& options) {
  return std::max(seen_fraction(a, b, camera, options), seen_fraction(b, a, camera, options));
}

}  // namespace nav::sim
