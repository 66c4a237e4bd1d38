#pragma once
// Small planar geometry for the survey simulator: convex hulls, convex polygon intersection
// (image footprint overlap) and polygon areas, in world NED x (north), y (east), metres.

#include <vector>

namespace nav::sim {

struct Point2 {
  double x_m = 0.0;
  double y_m = 0.0;
};
using Polygon2 = std::vector<Point2>;

/// Signed area (positive when the vertices run counter-clockwise in the x-y plane), m^2.
double signed_area_m2(const Polygon2& polygon);
/// |signed_area_m2|.
double area_m2(const Polygon2& polygon);
/// Convex hull (Andrew's monotone chain), counter-clockwise, no repeated end vertex.
Polygon2 convex_hull(std::vector<Point2> points);
/// Intersection of two convex polygons (Sutherland-Hodgman clipping of `subject` by each edge
/// of `clip`); either orientation; empty when they do not overlap.
Polygon2 intersect_convex(const Polygon2& subject, const Polygon2& clip);

}  // namespace nav::sim
