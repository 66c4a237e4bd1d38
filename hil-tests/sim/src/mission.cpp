#include "nav/sim/mission.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nav::sim {

const char* MissionOptions::validate() const {
  if (images < 2) return "images: must be >= 2";
  if (!(image_period_s > 0.1 && image_period_s < 3600.0))
    return "image_period_s: outside (0.1, 3600) s";
  if (!(speed_mps >= 0.05 && speed_mps <= 3.0)) return "speed_mps: outside [0.05, 3] m/s";
  if (!(line_length_m >= 2.0 && line_length_m <= 1000.0))
    return "line_length_m: outside [2, 1000] m";
  if (!(line_spacing_m >= 0.1 && line_spacing_m <= 100.0))
    return "line_spacing_m: outside [0.1, 100] m";
  if (!(altitude_m >= 0.5 && altitude_m <= 100.0)) return "altitude_m: outside [0.5, 100] m";
  return "";
}

Mission plan_mission(const MissionOptions& o) {
  if (const std::string err = o.validate(); !err.empty())
    throw std::invalid_argument("MissionOptions." + err);
  const double line_m = o.line_length_m + o.line_spacing_m;
  // Distance flown while imaging, with ~10 % lost to slowing down in the turns.
  const double imaging_m = 0.9 * o.images * o.image_period_s * o.speed_mps;
  const int lines = std::max(2, static_cast<int>(std::ceil(imaging_m / line_m)));
  Mission m;
  m.stern_lines = lines;
  m.bow_lines = lines;
  const double s = o.line_spacing_m, w = o.line_length_m;
  double y = 0.0;
  m.waypoints.push_back({0.0, 0.0, true});
  auto line = [&](double x, bool camera_on) {
    const double y_end = (y == 0.0) ? w : 0.0;
    m.waypoints.push_back({x, y, camera_on});  // step across to the line start (or transit)
    m.waypoints.push_back({x, y_end, true});
    y = y_end;
  };
  for (int k = 0; k < m.stern_lines; ++k) {
    if (k == 0) {
      m.waypoints.push_back({0.0, w, true});
      y = w;
    } else {
      line(-k * s, true);
    }
  }
  m.transit_end = m.waypoints.size();
  for (int k = 1; k <= m.bow_lines; ++k) line(k * s, k > 1);  // first: transit, camera off
  m.wreck_x_m = 0.0;
  m.wreck_y_m = 0.5 * w;
  const double margin = 15.0;
  m.extent = {-m.stern_lines * s - margin, (m.bow_lines + 1) * s + margin, -margin, w + margin};
  return m;
}

Guidance::Guidance(const Mission& mission, double lookahead_m)
    : mission_(&mission), lookahead_m_(lookahead_m) {
  if (mission.waypoints.size() < 2) throw std::invalid_argument("Guidance: fewer than 2 waypoints");
}

Guidance::Command Guidance::update(double x_m, double y_m) {
  const std::vector<Waypoint>& wp = mission_->waypoints;
  const int last = static_cast<int>(wp.size()) - 1;
  while (segment_ < last) {
    const Waypoint& a =
        has_start_override_ ? start_override_ : wp[static_cast<std::size_t>(segment_)];
    const Waypoint& b = wp[static_cast<std::size_t>(segment_ + 1)];
    const double len = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    const double along =
        len > 0.0 ? ((x_m - a.x_m) * (b.x_m - a.x_m) + (y_m - a.y_m) * (b.y_m - a.y_m)) / len : len;
    if (along < len) break;
    has_start_override_ = false;
    if (transit_requested_ && at_line_end() &&
        segment_ + 2 < static_cast<int>(mission_->transit_end)) {
      start_override_ = wp[static_cast<std::size_t>(segment_ + 1)];
      has_start_override_ = true;
      segment_ = static_cast<int>(mission_->transit_end) - 1;
      transit_requested_ = false;
      continue;
    }
    ++segment_;
  }
  Command c;
  if (segment_ >= last) {
    c.finished = true;
    c.camera_on = wp.back().camera_on;
    return c;
  }
  const Waypoint& a =
      has_start_override_ ? start_override_ : wp[static_cast<std::size_t>(segment_)];
  const Waypoint& b = wp[static_cast<std::size_t>(segment_ + 1)];
  const double chi = std::atan2(b.y_m - a.y_m, b.x_m - a.x_m);
  // Cross-track error, positive when the vehicle is to starboard of the path.
  const double e = -(x_m - a.x_m) * std::sin(chi) + (y_m - a.y_m) * std::cos(chi);
  c.heading_rad = chi - std::atan(e / lookahead_m_);
  c.camera_on = b.camera_on;
  return c;
}

bool Guidance::at_line_end() const {
  // Stern-leg lines end at odd waypoint indices (0: start, 1: end of line 0, 2: start of line
  // 1, 3: its end, ...); the current segment_ has just been completed.
  return segment_ % 2 == 0 && static_cast<std::size_t>(segment_ + 1) < mission_->transit_end;
}

}  // namespace nav::sim
