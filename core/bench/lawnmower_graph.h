#pragma once
// A synthetic survey pose graph for the recovery benchmarks: tracklines of a lawnmower pattern
// with odometry along the path and camera-overlap links across tracks, of any size.
#include <cmath>

#include "nav/core/geometry/pose.h"
#include "nav/core/posegraph/g2o.h"

namespace nav::core::bench {

/// Lawnmower survey: `rows` tracklines of `cols` poses, 2 m apart along track and 4 m across;
/// odometry along the path and a cross-track link to the pose beside it on the previous line
/// at every second pose (camera overlap). Estimates and measurements are exact.
inline PoseGraph lawnmower_graph(int rows, int cols) {
  PoseGraph g;
  auto pose_at = [&](int r, int c) {
    const bool forward = r % 2 == 0;
    Vec6 x = Vec6::Zero();
    x[0] = 2.0 * (forward ? c : cols - 1 - c);
    x[1] = 4.0 * r;
    x[5] = forward ? 0.0 : M_PI;
    return x;
  };
  Mat6 information = Mat6::Identity();
  information.topLeftCorner<3, 3>() *= 100.0;      // 10 cm
  information.bottomRightCorner<3, 3>() *= 3.0e3;  // ~1 deg
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int id = r * cols + c;
      g.vertices.push_back(G2oVertex{id, pose_at(r, c)});
    }
  }
  auto add_edge = [&](int a, int b) {
    G2oEdge e;
    e.from = e.from_index = a;
    e.to = e.to_index = b;
    e.measurement = tail_to_tail(g.vertices[static_cast<size_t>(a)].pose,
                                 g.vertices[static_cast<size_t>(b)].pose);
    e.information = information;
    e.information_g2o = information;
    e.line = 0;
    g.edges.push_back(e);
  };
  const int n = rows * cols;
  for (int k = 1; k < n; ++k) add_edge(k - 1, k);
  for (int r = 1; r < rows; ++r) {
    for (int c = 0; c < cols; c += 2) {
      // Same along-track position on the previous line (reversed direction).
      add_edge((r - 1) * cols + (cols - 1 - c), r * cols + c);
    }
  }
  return g;
}

}  // namespace nav::core::bench
