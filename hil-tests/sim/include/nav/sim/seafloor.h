#pragma once
// The simulated seafloor: a height field on a regular grid (default 0.1 m) in world NED, with a
// shipwreck-like relief after the RMS Titanic bow section (RSS 2005 survey site): a hull 28 m
// in beam standing ~10 m proud of the mud on a north-south axis, a raised boat deck and
// deckhouses, a break towards the stern with a debris field, a sediment berm along the hull,
// and a gently sloping, undulating seafloor at ~3,800 m. Deterministic from the seed.
// Depth is positive down (z of core/README.md).

#include <cstdint>
#include <vector>

namespace nav::sim {

struct SeafloorOptions {
  double mean_depth_m = 3800.0;     ///< seafloor depth at the wreck's midship
  double resolution_m = 0.1;        ///< grid spacing of the height field
  double hull_beam_m = 28.0;        ///< hull width
  double hull_height_m = 10.0;      ///< deck height above the mud
  double break_x_m = -30.0;         ///< hull ends (broken) south of this x (site frame)
  double clearance_radius_m = 3.0;  ///< safe_depth_m looks this far around the vehicle
};

/// Axis-aligned extent of the grid in world x (north), y (east).
struct GridExtent {
  double x_min_m = -60.0, x_max_m = 60.0;
  double y_min_m = -40.0, y_max_m = 40.0;
};

class Seafloor {
 public:
  /// Builds the height field over `extent`; the wreck's midship is at world (wreck_x_m,
  /// wreck_y_m) with its keel along x (bow north).
  Seafloor(const GridExtent& extent, double wreck_x_m, double wreck_y_m,
           const SeafloorOptions& options, std::uint64_t seed);

  /// Seafloor depth (m, down) at world x, y: bilinear in the grid, clamped at its edge.
  double depth_m(double x_m, double y_m) const;
  /// The shallowest seafloor within ~clearance_radius_m (square window), smoothed: the
  /// depth a vehicle must stay above to clear the relief ahead in any direction.
  double safe_depth_m(double x_m, double y_m) const;
  /// Height of the relief above the flat seafloor at x, y (m), for rendering and tests.
  double relief_height_m(double x_m, double y_m) const;

  const GridExtent& extent() const { return extent_; }
  const SeafloorOptions& options() const { return options_; }
  int columns() const { return nx_; }
  int rows() const { return ny_; }

 private:
  struct Grid {
    double x0_m = 0.0, y0_m = 0.0, step_m = 1.0;
    int nx = 0, ny = 0;
    std::vector<float> values;  ///< row-major, index = iy * nx + ix
    double sample(double x_m, double y_m) const;
  };
  struct Wave {
    double kx = 0.0, ky = 0.0, phase = 0.0, amplitude_m = 0.0;
  };
  double flat_depth_m(double x_m, double y_m) const;
  void build_relief(std::uint64_t seed);
  void build_safe_depth();

  GridExtent extent_;
  SeafloorOptions options_;
  int nx_ = 0, ny_ = 0;
  double wreck_x_m_ = 0.0, wreck_y_m_ = 0.0;
  std::vector<Wave> waves_;  ///< undulations of the flat seafloor
  Grid depth_;               ///< seafloor depth, m
  Grid safe_;                ///< safe_depth_m on a coarse grid
};

}  // namespace nav::sim
