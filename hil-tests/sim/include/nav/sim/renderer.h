#pragma once
// Renders the simulated camera's 12-bit grey frames from the seafloor height field
// (`navtool simulate --render-images`): per pixel, the ray of the pinhole camera (config
// intrinsics, no distortion, config mount) meets the height field (first crossing of the
// bilinear surface by ray marching and bisection, walls included); the seafloor's albedo is a
// seeded multi-scale value-noise texture (sediment, brighter rocks and debris tops), walls
// textured in their own plane; a strobe beside the camera lights it with Lambert shading,
// inverse-square falloff and exponential attenuation in sea water along strobe -> seafloor ->
// camera; backscatter of the strobe light by the water along each ray (single scattering);
// cos^4 vignetting; shot and read noise; 12 significant bits.

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/sim/oracle.h"
#include "nav/sim/seafloor.h"

namespace nav::sim {

struct RenderOptions {
  core::Vec3 strobe_in_camera_m{0.0, -0.8, 0.0};  ///< strobe 0.8 m "up" in the image (aft)
  double attenuation_per_m = 0.25;                ///< sea-water extinction coefficient, 1/m
  double target_counts = 1500.0;                  ///< auto exposure: mean of the central half
  double backscatter_per_m_sr = 1.5e-4;  ///< volume scattering function at 180 deg, 1/(m sr)
  double read_noise_counts = 3.0;                 ///< 1 sigma
  double counts_per_electron = 0.25;              ///< shot noise: sqrt(signal / gain) electrons
  int thumbnail_width_px = 160;
};

class Renderer {
 public:
  Renderer(const CameraGeometry& camera, const Seafloor& seafloor, const RenderOptions& options,
           std::uint64_t seed);
  /// The frame (CV_16UC1, 2cy x 2cx, values 0..4095) seen from the true state `x`; the auto
  /// exposure's gain relative to a floor 1 m below the camera goes to *gain_db.
  cv::Mat render(const core::Vec12& x, std::uint64_t frame_seed, double* gain_db = nullptr) const;
  /// Albedo of the seafloor at world x, y standing `relief_m` above the flat seafloor
  /// (Seafloor::relief_height_m), averaged over a pixel footprint of footprint_m (0: the
  /// point's own): a property of the point and the pixel's size, not of the camera's pose.
  double albedo(double x_m, double y_m, double relief_m, double footprint_m = 0.0) const;
  /// Albedo of the surface point q_m (world NED, m) of unit normal `normal`: the planar texture
  /// above projected onto the surface by triplanar mapping, so walls are textured in their own
  /// plane. Equal to albedo(q.x, q.y, ...) where the normal is vertical.
  double albedo(const core::Vec3& q_m, const core::Vec3& normal, double relief_m,
                double footprint_m) const;
  /// The first point of the ray p_world + t d_world (t > 0, d_world.z > 0: looking down) on the
  /// height field, as render() finds each pixel's (world NED, m).
  core::Vec3 surface_point(const core::Vec3& p_world, const core::Vec3& d_world) const;
  /// surface_point of each ray from one camera position (one bound map for all); NaN for a
  /// ray with d.z <= 0.05 (near or above the horizon).
  std::vector<core::Vec3> surface_points(const core::Vec3& p_world,
                                         const std::vector<core::Vec3>& d_world) const;
  const RenderOptions& options() const { return options_; }
  /// 8-bit thumbnail (width thumbnail_width_px, aspect kept) of a 12-bit frame.
  cv::Mat thumbnail(const cv::Mat& frame) const;

 private:
  double value_noise(double x, double y, std::uint64_t octave_seed) const;
  /// Lower bound of the seafloor depth (its shallowest) per 1 m cell around a camera.
  struct TopMap {
    static constexpr int kCells = 30;
    double x0_m = 0.0, y0_m = 0.0, overall_m = 0.0;
    std::vector<double> depth_m;  ///< row-major kCells x kCells
    double at(double x_m, double y_m) const;
  };
  TopMap top_map(const core::Vec3& p_cam) const;
  /// Ray parameter t of the first point of p + t d (d.z > 0) at or below the height field.
  double first_hit(const core::Vec3& p, const core::Vec3& d, const TopMap& top) const;
  /// Backscattered strobe light per pixel (CV_32F counts) for a floor range_m away.
  cv::Mat backscatter(const core::Vec3& p_cam, const core::Mat3& R_world_cam,
                      const core::Vec3& p_strobe, double range_m, double exposure) const;

  CameraGeometry camera_;
  const Seafloor* seafloor_;
  RenderOptions options_;
  std::uint64_t seed_;
};

}  // namespace nav::sim
