// Report figures: see figures.h.
#include "nav/report/figures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include "nav/report/csv_table.h"

namespace nav::report {
namespace {

std::string fmt(const char* format, double v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

/// Map coordinates of a pose: (East, North) = (y_m, x_m).
cv::Point2d map_xy(const core::Vec6& pose) { return {pose[1], pose[0]}; }

/// XY covariance in map coordinates (East, North).
cv::Matx22d map_cov(const core::Mat6& cov) { return {cov(1, 1), cov(1, 0), cov(0, 1), cov(0, 0)}; }

struct Bounds {
  double x_min = INFINITY, x_max = -INFINITY, y_min = INFINITY, y_max = -INFINITY;
  void add(const cv::Point2d& p) {
    x_min = std::min(x_min, p.x);
    x_max = std::max(x_max, p.x);
    y_min = std::min(y_min, p.y);
    y_max = std::max(y_max, p.y);
  }
  bool empty() const { return !(x_max >= x_min); }
};

std::vector<cv::Point2d> map_points(const std::vector<TimedPose>& poses, Bounds& bounds) {
  std::vector<cv::Point2d> pts;
  pts.reserve(poses.size());
  for (const auto& p : poses) {
    pts.push_back(map_xy(p.pose));
    bounds.add(pts.back());
  }
  return pts;
}

double nice_at_least(double x) {
  if (!(x > 1.0)) return 1.0;
  const double mag = std::pow(10.0, std::floor(std::log10(x)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * mag >= x) return m * mag;
  }
  return 10.0 * mag;
}

double major_sigma(const core::Mat6& cov) {
  const double a = cov(0, 0), b = cov(0, 1), c = cov(1, 1);
  const double half_trace = 0.5 * (a + c);
  const double d = std::sqrt(std::max(0.0, 0.25 * (a - c) * (a - c) + b * b));
  return std::sqrt(std::max(0.0, half_trace + d));
}

}  // namespace

cv::Mat trajectory_figure(const std::vector<TimedPose>& dead_reckoning,
                          const std::vector<TimedPose>& slam, const std::vector<TimedPose>& truth,
                          const std::string& subtitle, const PlotStyle& style_in) {
  // Truth over the replayed span only (a replay may cover part of the dive).
  std::vector<TimedPose> truth_span;
  for (const auto& p : truth) {
    if (slam.empty() || (p.t_us >= slam.front().t_us && p.t_us <= slam.back().t_us)) {
      truth_span.push_back(p);
    }
  }
  Bounds b;
  const auto truth_pts = map_points(truth_span, b);
  const auto dr_pts = map_points(dead_reckoning, b);
  const auto slam_pts = map_points(slam, b);
  if (b.empty()) throw ReportError("Fig. 1: no trajectory rows to draw");
  PlotStyle style = style_in;
  style.equal_aspect = true;
  Plot plot(b.x_min, b.x_max, b.y_min, b.y_max, style);
  plot.set_title("Fig. 1  Vehicle trajectory (XY): dead reckoning, SLAM, truth");
  plot.set_subtitle(subtitle);
  plot.set_labels("East y [m]", "North x [m]");
  if (!truth_pts.empty()) {
    plot.polyline(truth_pts, colors::kBlack, 2);
    plot.add_legend("truth (truth.csv)", colors::kBlack);
  }
  plot.polyline(dr_pts, colors::kRed, 2);
  plot.add_legend("dead reckoning", colors::kRed);
  plot.polyline(slam_pts, colors::kBlue, 2);
  plot.add_legend("SLAM (running estimate)", colors::kBlue);
  if (!slam_pts.empty()) plot.markers({slam_pts.front()}, colors::kGreen, 5);
  plot.add_note("green dot: start");
  return plot.image();
}

Sparsity sparsity_of(const BlockPattern& pattern) {
  Sparsity s;
  s.dim = static_cast<long long>(pattern.block_dim) * pattern.num_blocks;
  long long blocks = 0;
  for (const auto& [i, j] : pattern.blocks) blocks += (i == j) ? 1 : 2;
  s.nonzeros = blocks * pattern.block_dim * pattern.block_dim;
  s.nonzero_fraction = s.dim > 0 ? static_cast<double>(s.nonzeros) /
                                       (static_cast<double>(s.dim) * static_cast<double>(s.dim))
                                 : 0.0;
  return s;
}

cv::Mat sparsity_figure(const BlockPattern& pattern, const PlotStyle& style_in) {
  const Sparsity s = sparsity_of(pattern);
  PlotStyle style = style_in;
  style.equal_aspect = true;
  style.y_down = true;
  const double n = static_cast<double>(s.dim), d = pattern.block_dim;
  Plot plot(0.0, n, 0.0, n, style);
  plot.set_title("Fig. 2  Information matrix: " + std::to_string(s.dim) + " x " +
                 std::to_string(s.dim) + ", " + fmt("%.3g", 100.0 * s.nonzero_fraction) +
                 " % non-zero");
  plot.set_subtitle(std::to_string(pattern.num_blocks) + " states of " +
                    std::to_string(pattern.block_dim) + " elements, " +
                    std::to_string(pattern.blocks.size()) + " non-zero blocks (i <= j)");
  plot.set_labels("column (state element)", "row (state element)");
  plot.rect({0.0, 0.0}, {n, n}, colors::kGrey, 1);
  for (const auto& [i, j] : pattern.blocks) {
    const double bi = static_cast<double>(i) * d, bj = static_cast<double>(j) * d;
    plot.fill_rect({bj, bi}, {bj + d, bi + d}, colors::kBlue);
    plot.fill_rect({bi, bj}, {bi + d, bj + d}, colors::kBlue);
  }
  plot.add_legend("non-zero block", colors::kBlue, true);
  return plot.image();
}

cv::Mat logdet_histogram_figure(const std::vector<double>& ours,
                                const std::vector<double>& markov_blanket, int bins,
                                const std::string& title, const PlotStyle& style) {
  if (ours.empty() && markov_blanket.empty()) {
    throw ReportError("Fig. 3: no log-determinant ratios to draw");
  }
  bins = std::max(bins, 1);
  double lo = INFINITY, hi = -INFINITY;
  for (const auto* v : {&ours, &markov_blanket}) {
    for (double x : *v) {
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  }
  lo = std::min(lo, 0.0);  // the zero line is always in view
  hi = std::max(hi, 0.0);
  if (!(hi > lo)) hi = lo + 1.0;
  const double width = (hi - lo) / bins;
  auto count = [&](const std::vector<double>& v) {
    std::vector<int> c(static_cast<size_t>(bins), 0);
    for (double x : v)
      ++c[static_cast<size_t>(std::clamp(static_cast<int>((x - lo) / width), 0, bins - 1))];
    return c;
  };
  const auto c_ours = count(ours), c_mb = count(markov_blanket);
  const int peak = std::max(*std::max_element(c_ours.begin(), c_ours.end()),
                            *std::max_element(c_mb.begin(), c_mb.end()));
  Plot plot(lo, hi, 0.0, 1.3 * peak, style);  // headroom: the legend sits top right
  plot.set_title(title);
  auto share = [](const std::vector<double>& v) {
    const auto pos = std::count_if(v.begin(), v.end(), [](double x) { return x >= 0.0; });
    return std::to_string(pos) + " of " + std::to_string(v.size()) + " >= 0";
  };
  std::string sub = "positive = conservative (larger than exact); ours: " + share(ours);
  if (!markov_blanket.empty()) sub += "; Markov blanket: " + share(markov_blanket);
  plot.set_subtitle(sub);
  plot.set_labels("log( det S_approx / det S_exact )", "count");
  const bool both = !ours.empty() && !markov_blanket.empty();
  for (int k = 0; k < bins; ++k) {
    const double x0 = lo + k * width;
    const double split = both ? x0 + 0.5 * width : x0 + width;
    if (!ours.empty() && c_ours[static_cast<size_t>(k)] > 0) {
      plot.fill_rect({x0, 0.0}, {split, static_cast<double>(c_ours[static_cast<size_t>(k)])},
                     colors::kBlue);
    }
    if (!markov_blanket.empty() && c_mb[static_cast<size_t>(k)] > 0) {
      plot.fill_rect({both ? split : x0, 0.0},
                     {x0 + width, static_cast<double>(c_mb[static_cast<size_t>(k)])},
                     colors::kOrange);
    }
  }
  plot.vline_dashed(0.0, colors::kBlack, 2);
  if (!ours.empty()) plot.add_legend("ours (conservative bound)", colors::kBlue, true);
  if (!markov_blanket.empty()) plot.add_legend("Markov blanket", colors::kOrange, true);
  plot.add_legend("zero: exact", colors::kBlack);
  plot.add_note(std::to_string(bins) + " bins of width " + fmt("%.3g", width));
  return plot.image();
}

double automatic_inflation(const std::vector<DelayedState>& states, double sigmas) {
  if (states.empty()) return 1.0;
  Bounds b;
  std::vector<double> radii;
  for (const auto& s : states) {
    b.add(map_xy(s.pose));
    radii.push_back(sigmas * major_sigma(s.bound));
  }
  std::nth_element(radii.begin(), radii.begin() + static_cast<long>(radii.size() / 2), radii.end());
  const double median = radii[radii.size() / 2];
  const double extent = std::max(b.x_max - b.x_min, b.y_max - b.y_min);
  if (!(median > 0.0) || !(extent > 0.0)) return 1.0;
  return nice_at_least(0.015 * extent / median);
}

cv::Mat network_figure(const std::vector<DelayedState>& states,
                       const std::vector<ProposedLink>& links, const NetworkOptions& options,
                       const PlotStyle& style_in) {
  if (states.empty()) throw ReportError("Fig. 5: states.csv has no delayed states");
  const double inflation =
      options.inflation > 0.0 ? options.inflation : automatic_inflation(states, options.sigmas);
  const double scale = options.sigmas * inflation;
  std::map<long long, cv::Point2d> at;
  Bounds b;
  for (const auto& s : states) {
    at[s.state_id] = map_xy(s.pose);
    b.add(at[s.state_id]);
    // Keep the ellipses inside the view.
    const double r = scale * major_sigma(s.bound);
    b.add(at[s.state_id] + cv::Point2d(r, r));
    b.add(at[s.state_id] - cv::Point2d(r, r));
  }
  PlotStyle style = style_in;
  style.equal_aspect = true;
  Plot plot(b.x_min, b.x_max, b.y_min, b.y_max, style);
  // Temporal links: consecutive delayed states (states are sorted by id).
  for (size_t k = 1; k < states.size(); ++k) {
    plot.segment(map_xy(states[k - 1].pose), map_xy(states[k].pose), colors::kGrey, 1);
  }
  std::set<std::pair<long long, long long>> spatial;
  for (const auto& l : links) {
    if (l.outcome != "accepted") continue;
    const auto a = at.find(l.state_i), c = at.find(l.state_j);
    if (a == at.end() || c == at.end()) continue;
    if (!spatial.emplace(std::min(l.state_i, l.state_j), std::max(l.state_i, l.state_j)).second) {
      continue;  // the same pair accepted again: one edge in the network
    }
    plot.segment(a->second, c->second, colors::kGreen, 1);
  }
  const size_t stride = std::max<size_t>(
      1, (states.size() + options.max_ellipses - 1) / std::max(options.max_ellipses, 1));
  bool have_initial = false;
  for (size_t k = 0; k < states.size(); k += stride) {
    const auto& s = states[k];
    const cv::Point2d c = map_xy(s.pose);
    if (s.initial) {
      plot.ellipse(c, map_cov(*s.initial), scale, colors::kMagenta, 1);
      have_initial = true;
    }
    plot.ellipse(c, map_cov(s.bound), scale, colors::kBlue, 1);
    plot.ellipse(c, map_cov(s.exact), scale, colors::kRed, 1);
  }
  std::vector<cv::Point2d> nodes;
  for (const auto& s : states) nodes.push_back(map_xy(s.pose));
  plot.markers(nodes, colors::kBlack, 2);

  plot.set_title("Fig. 5  Pose-constraint network and 3-sigma XY bounds");
  plot.set_subtitle(std::to_string(states.size()) + " delayed states, " +
                    std::to_string(states.size() - 1) + " temporal and " +
                    std::to_string(spatial.size()) + " spatial (accepted camera) links");
  plot.set_labels("East y [m]", "North x [m]");
  plot.add_legend("temporal link", colors::kGrey);
  plot.add_legend("spatial link (camera)", colors::kGreen);
  plot.add_legend(have_initial ? "initial bound" : "initial bound (not in states.csv)",
                  colors::kMagenta);
  plot.add_legend("current conservative bound", colors::kBlue);
  plot.add_legend("exact marginal", colors::kRed);
  plot.add_note(fmt("%g-sigma ellipses inflated x", options.sigmas) + fmt("%g", inflation));
  if (stride > 1) plot.add_note("ellipses of 1 in " + std::to_string(stride) + " states");
  return plot.image();
}

}  // namespace nav::report
