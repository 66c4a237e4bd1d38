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
};

struct VisibleFootprint {
  core::Vec6 x_world_camera = core::Vec6::Zero();
  int cols = 0, rows = 0;                ///< grid of pixels (c * step_px, r * step_px)
  std::vector<core::Vec3> points_world;  ///< per grid pixel, row-major
  std::vector<double> depth_m;           ///< z in the camera of each point
};

/// The grid of frame x_world_camera's pixels cast onto the scene.
VisibleFootprint visible_footprint(const Renderer& renderer, const CameraGeometry& camera,
                                   const core::Vec6& x_world_camera,
                                   const VisibleFootprintOptions& options = {});

/// Fraction of a's surface points within range that b sees too (0 when a has none).
double seen_fraction(const VisibleFootprint& a, const VisibleFootprint& b,
                     const CameraGeometry& camera, const VisibleFootprintOptions& options = {});

/// max(seen_fraction(a, b), seen_fraction(b, a)): the common surface as a fraction of the
/// smaller view, as RegistrationOracle::overlap_fraction is for flat footprints.
double visible_overlap(const VisibleFootprint& a, const VisibleFootprint& b,
                       const CameraGeometry& camera, const VisibleFootprintOptions& options = {});

}  // namespace nav::sim
