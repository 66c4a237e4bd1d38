#pragma once
// The survey mission, after the RMS Titanic survey of Eustice et al. (RSS 2005): a
// boustrophedon grid of athwartships track lines over the wreck, first from midship towards the
// stern, then a transit back to midship with the camera OFF, then midship towards the bow, so
// that imaging resumes over the first lines (a large loop closure). World NED, origin at the
// start of the first line; lines run east (+y) and west, stepping south (stern leg) or north
// (bow leg); the wreck's keel runs north-south under the middle of the lines.

#include <cstddef>
#include <vector>

#include "nav/sim/seafloor.h"

namespace nav::sim {

struct MissionOptions {
  int images = 866;             ///< the dive ends after this many images
  double image_period_s = 8.0;  ///< one image every 8 s while the camera is on
  double speed_mps = 0.5;       ///< commanded speed on the track lines
  double line_length_m = 40.0;  ///< athwartships track line length
  double line_spacing_m = 1.4;  ///< distance between neighbouring lines
  double altitude_m = 4.0;      ///< vehicle reference point above the safe relief depth
  /// Empty when valid, else the field and the reason.
  [[nodiscard]] const char* validate() const;
};

struct Waypoint {
  double x_m = 0.0;
  double y_m = 0.0;
  bool camera_on = true;  ///< camera state on the segment that ends at this waypoint
};

struct Mission {
  std::vector<Waypoint> waypoints;          ///< waypoints[0] is the start (0, 0)
  double wreck_x_m = 0.0, wreck_y_m = 0.0;  ///< midship, keel along x
  GridExtent extent;                        ///< area the seafloor must cover
  int stern_lines = 0, bow_lines = 0;       ///< planned (generous: see Guidance::request_transit)
  std::size_t transit_end = 0;              ///< waypoint index where the camera-off transit ends
};

/// Plans twice the lines `images` images need at the commanded speed on each leg (the
/// simulation ends the stern leg when half the images are taken, Guidance::request_transit,
/// and the dive at the last image). Throws std::invalid_argument naming a bad option.
Mission plan_mission(const MissionOptions& options);

/// Line-of-sight path following along the waypoint segments.
class Guidance {
 public:
  explicit Guidance(const Mission& mission, double lookahead_m = 2.0);
  struct Command {
    double heading_rad = 0.0;  ///< desired heading
    bool camera_on = true;
    bool finished = false;  ///< past the last waypoint
  };
  /// Advances past reached segments and returns the command at world position x, y.
  Command update(double x_m, double y_m);
  int segment() const { return segment_; }
  /// At the end of the current stern-leg line, go straight to the transit's end (camera off).
  void request_transit() { transit_requested_ = true; }

 private:
  bool at_line_end() const;

  const Mission* mission_;
  double lookahead_m_;
  int segment_ = 0;  ///< current segment: waypoints[segment_] -> waypoints[segment_ + 1]
  bool transit_requested_ = false;
  bool has_start_override_ = false;  ///< the transit starts where the vehicle left its line
  Waypoint start_override_;
};

}  // namespace nav::sim
