#pragma once
// What a simulated camera sees of the seafloor, hull and debris, and how much two frames see in
// common: the truth behind "pairs whose true footprints overlap" on a 3-D scene.
//
// The flat footprint (oracle.h image_footprint: the image's corner rays on the plane at the
// depth below the camera) misjudges frames over the wreck: a camera above a hull edge sees the
// deck at 4 m and the mud at 12 m, and two such frames can share little of either. Here a grid
// of pixels is cast onto the height field as the renderer casts them (Renderer::surface_points:
// first crossing, walls included), and a surface point of frame a counts as seen by frame b when
// it projects inside b's image and b's own ray through that pixel ends at it (not in front of
// it: occluded), within max(occlusion_tolerance_m, occlusion_tolerance_fraction x depth).
// Surface farther than max_range_m from a camera is not in its footprint: with the renderer's
// default sea water (0.25 / m) and strobe, the floor 8 m away returns 1/30 of the light of the
// floor 4 m away and is at the read noise beside a metered hull top; a camera sees haze there.
// Nor is surface lit too little for the frame's exposure: the renderer meters the mean of the
// central half of the image, so next to a deck 4 m away the mud 8 m away is at a few counts.
// A point's relative return is that of a white, strobe-facing surface, exp(-c (r_s + r_c)) /
// r_s^2 (r_s, r_c its range from strobe and camera, c the renderer's attenuation); the frame's
// metered return is its mean over the central half of the cast grid (rays that meet nothing
// count 0); the point is in the footprint when its return is at least min_relative_return of
// that (1/15: ~100 of the metered mean's 1,500 counts, where the texture's +-30 % stands ~5x
// above the shot and read noise). Albedo, Lambert shading and backscatter are left out.
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/sim/oracle.h"
#include "nav/sim/renderer.h"

namespace nav::sim {

struct VisibleFootprintOptions {
  int step_px = 16;  ///< grid spacing of the cast pixels
  double occlusion_tolerance_m = 0.1;
  double occlusion_tolerance_fraction = 0.05;
  double max_range_m = 8.0;  ///< farther surface is not seen (see above)
  /// Less lit surface, relative to the frame's metered return, is not seen (see above; 0: the
  /// range rule alone).
  double min_relative_return = 1.0 / 15.0;
  /// seen_fraction's denominator: all of a's cast pixels (true), or only those of its footprint
  /// (false; see above).
  bool of_image = true;
};

struct VisibleFootprint {
  core::Vec6 x_world_camera = core::Vec6::Zero();
  int cols = 0, rows = 0;                ///< grid of pixels (c * step_px, r * step_px)
  std::vector<core::Vec3> points_world;  ///< per grid pixel, row-major
  std::vector<double> depth_m;           ///< z in the camera of each point
  core::Vec3 strobe_world = core::Vec3::Zero();
  double attenuation_per_m = 0.0;
  double metered_return = 0.0;  ///< mean relative return of the central half (see above)
};

/// exp(-c (r_s + r_c)) / r_s^2 of the surface point q_world in frame f (see above).
double relative_return(const VisibleFootprint& f, const core::Vec3& q_world);

/// Whether the surface point q_world is within frame f's range and lit enough for its exposure
/// (see above); false for a NaN point. Occlusion is seen_fraction's test.
bool in_footprint(const VisibleFootprint& f, const core::Vec3& q_world,
                  const VisibleFootprintOptions& options = {});

/// The grid of frame x_world_camera's pixels cast onto the scene.
VisibleFootprint visible_footprint(const Renderer& renderer, const CameraGeometry& camera,
                                   const core::Vec6& x_world_camera,
                                   const VisibleFootprintOptions& options = {});

/// Fraction of a's cast pixels (of_image) or of its footprint's points (!of_image) whose
/// surface point is in both footprints and unoccluded in b (0 when a has none).
double seen_fraction(const VisibleFootprint& a, const VisibleFootprint& b,
                     const CameraGeometry& camera, const VisibleFootprintOptions& options = {});

/// max(seen_fraction(a, b), seen_fraction(b, a)): the common surface as a fraction of the
/// image, as RegistrationOracle::overlap_fraction is over a flat floor (where the footprint is
/// the whole image). Of the smaller footprint instead (!of_image), a frame whose lit surface is
/// a sliver beside haze overlaps 100 % with any frame that sees that sliver.
double visible_overlap(const VisibleFootprint& a, const VisibleFootprint& b,
                       const CameraGeometry& camera, const VisibleFootprintOptions& options = {});

}  // namespace nav::sim
