#include "nav/sim/geometry2d.h"

#include <algorithm>
#include <cmath>

namespace nav::sim {
namespace {

double cross(const Point2& o, const Point2& a, const Point2& b) {
  return (a.x_m - o.x_m) * (b.y_m - o.y_m) - (a.y_m - o.y_m) * (b.x_m - o.x_m);
}

Polygon2 counter_clockwise(const Polygon2& p) {
  if (signed_area_m2(p) >= 0.0) return p;
  return Polygon2(p.rbegin(), p.rend());
}

/// Point where segment a-b crosses the line through c-d (a and b on opposite sides).
Point2 line_crossing(const Point2& a, const Point2& b, const Point2& c, const Point2& d) {
  const double da = cross(c, d, a);
  const double db = cross(c, d, b);
  const double t = da / (da - db);
  return {a.x_m + t * (b.x_m - a.x_m), a.y_m + t * (b.y_m - a.y_m)};
}

}  // namespace

double signed_area_m2(const Polygon2& p) {
  double twice = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Point2& a = p[i];
    const Point2& b = p[(i + 1) % p.size()];
    twice += a.x_m * b.y_m - b.x_m * a.y_m;
  }
  return 0.5 * twice;
}

double area_m2(const Polygon2& p) { return std::abs(signed_area_m2(p)); }

Polygon2 convex_hull(std::vector<Point2> pts) {
  std::sort(pts.begin(), pts.end(), [](const Point2& a, const Point2& b) {
    return a.x_m < b.x_m || (a.x_m == b.x_m && a.y_m < b.y_m);
  });
  if (pts.size() < 3) return pts;
  Polygon2 hull(2 * pts.size());
  std::size_t k = 0;
  for (const Point2& p : pts) {  // lower hull
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0.0) --k;
    hull[k++] = p;
  }
  const std::size_t lower = k + 1;
  for (auto it = pts.rbegin() + 1; it != pts.rend(); ++it) {  // upper hull
    while (k >= lower && cross(hull[k - 2], hull[k - 1], *it) <= 0.0) --k;
    hull[k++] = *it;
  }
  hull.resize(k - 1);
  return hull;
}

Polygon2 intersect_convex(const Polygon2& subject_in, const Polygon2& clip_in) {
  Polygon2 out = counter_clockwise(subject_in);
  const Polygon2 clip = counter_clockwise(clip_in);
  for (std::size_t e = 0; e < clip.size() && !out.empty(); ++e) {
    const Point2& c = clip[e];
    const Point2& d = clip[(e + 1) % clip.size()];
    const Polygon2 in = out;
    out.clear();
    for (std::size_t i = 0; i < in.size(); ++i) {
      const Point2& a = in[i];
      const Point2& b = in[(i + 1) % in.size()];
      const bool a_in = cross(c, d, a) >= 0.0;
      const bool b_in = cross(c, d, b) >= 0.0;
      if (a_in) out.push_back(a);
      if (a_in != b_in) out.push_back(line_crossing(a, b, c, d));
    }
  }
  return out;
}

}  // namespace nav::sim
