// Fits and plots of the soak; see soak_analysis.h.
#include "soak_analysis.h"

#include <algorithm>
#include <cstdio>

#include "nav/report/plot.h"

namespace nav::campaign {
namespace {

/// CPU seconds per dive hour between consecutive samples, at the interval's end.
void cpu_rates(const std::vector<SoakSample>& s, std::vector<double>& x, std::vector<double>& y) {
  for (std::size_t i = 1; i < s.size(); ++i) {
    const double dh = s[i].dive_h - s[i - 1].dive_h;
    if (dh <= 0.0) continue;
    x.push_back(s[i].dive_h);
    y.push_back((s[i].cpu_s - s[i - 1].cpu_s) / dh);
  }
}

void plot_series(const std::vector<double>& x, const std::vector<double>& y,
                 std::pair<double, double> line, const std::string& title,
                 const std::string& y_label, const std::filesystem::path& path) {
  const auto [y_lo, y_hi] = std::minmax_element(y.begin(), y.end());
  report::PlotStyle style;
  style.width_px = 900;
  style.height_px = 450;
  report::Plot plot(x.front(), x.back(), std::min(0.0, *y_lo), *y_hi * 1.1, style);
  plot.set_title(title);
  plot.set_labels("dive time (h)", y_label);
  std::vector<cv::Point2d> points;
  for (std::size_t i = 0; i < x.size(); ++i) points.emplace_back(x[i], y[i]);
  plot.polyline(points, report::colors::kBlue, 2);
  plot.segment({x.front(), line.first + line.second * x.front()},
               {x.back(), line.first + line.second * x.back()}, report::colors::kRed, 2);
  plot.add_legend("navd", report::colors::kBlue);
  plot.add_legend("least squares after warm-up", report::colors::kRed);
  report::write_png(path.string(), plot.image());
}

}  // namespace

std::pair<double, double> fit_line(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sx += x[i];
    sy += y[i];
    sxx += x[i] * x[i];
    sxy += x[i] * y[i];
  }
  if (x.empty()) return {0.0, 0.0};
  const double den = n * sxx - sx * sx;
  if (x.size() < 2 || den <= 1e-12 * n * sxx) return {sy / n, 0.0};
  const double b = (n * sxy - sx * sy) / den;
  return {(sy - b * sx) / n, b};
}

SoakSummary analyse_soak(const std::vector<SoakSample>& samples, double warmup_dive_h) {
  SoakSummary r;
  r.samples = static_cast<int>(samples.size());
  if (samples.empty()) return r;
  r.dive_hours = samples.back().dive_h;
  r.wall_s = samples.back().wall_s;
  std::vector<SoakSample> kept;
  for (const SoakSample& s : samples) {
    if (s.dive_h >= warmup_dive_h) kept.push_back(s);
    r.max_queue_depth = std::max(r.max_queue_depth, s.queue_depth);
  }
  r.queue_drops = samples.back().queue_drops;
  r.late_measurements = samples.back().late_measurements;
  if (kept.size() < 2) return r;
  std::vector<double> x, rss;
  r.fds_min = r.fds_max = kept.front().fds;
  for (const SoakSample& s : kept) {
    x.push_back(s.dive_h);
    rss.push_back(s.rss_mb);
    r.fds_min = std::min(r.fds_min, s.fds);
    r.fds_max = std::max(r.fds_max, s.fds);
  }
  const auto [a, b] = fit_line(x, rss);
  r.rss_slope_mb_per_dive_h = b;
  r.rss_first_mb = a + b * x.front();
  r.rss_last_mb = a + b * x.back();
  r.rss_growth_percent = 100.0 * (r.rss_last_mb - r.rss_first_mb) / r.rss_first_mb;
  r.cpu_s_per_dive_h = (kept.back().cpu_s - kept.front().cpu_s) / (x.back() - x.front());
  std::vector<double> cx, cy;
  cpu_rates(kept, cx, cy);
  r.cpu_slope_per_dive_h = fit_line(cx, cy).second;
  return r;
}

void plot_soak(const std::vector<SoakSample>& samples, const SoakSummary& summary,
               const std::filesystem::path& dir) {
  if (samples.size() < 3) return;
  std::vector<double> x, rss;
  for (const SoakSample& s : samples) {
    x.push_back(s.dive_h);
    rss.push_back(s.rss_mb);
  }
  char title[160];
  std::snprintf(title, sizeof title,
                "navd VmRSS: slope %.3f MiB per dive hour, %+.2f %% over %.1f h",
                summary.rss_slope_mb_per_dive_h, summary.rss_growth_percent, summary.dive_hours);
  const double a = summary.rss_first_mb - summary.rss_slope_mb_per_dive_h * x.front();
  plot_series(x, rss, {a, summary.rss_slope_mb_per_dive_h}, title, "RSS (MiB)",
              dir / "soak_rss.png");
  std::vector<double> cx, cy;
  cpu_rates(samples, cx, cy);
  if (cx.size() < 2) return;
  const auto line = fit_line(cx, cy);
  std::snprintf(title, sizeof title, "navd CPU: %.1f s per dive hour, slope %.2f s/h per dive hour",
                summary.cpu_s_per_dive_h, summary.cpu_slope_per_dive_h);
  plot_series(cx, cy, line, title, "CPU s per dive hour", dir / "soak_cpu.png");
}

}  // namespace nav::campaign
