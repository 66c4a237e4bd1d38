#pragma once
// The soak's samples, their fits and plots (soak.h): ordinary least squares lines of RSS and of
// the per-interval CPU seconds per dive hour against dive hours, over the samples after the
// warm-up.
//
// Threads: plain functions.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "nav/campaign/soak.h"

namespace nav::campaign {

struct SoakSample {
  double wall_s = 0.0, dive_h = 0.0, rss_mb = 0.0, cpu_s = 0.0;
  int fds = 0, queue_depth = 0;
  std::int64_t queue_drops = 0, late_measurements = 0;
};

/// Least squares y = a + b x; {a, b}; {mean y, 0} with fewer than 2 distinct x.
std::pair<double, double> fit_line(const std::vector<double>& x, const std::vector<double>& y);

/// The summary's numbers from the samples (navd_* left as they are).
SoakSummary analyse_soak(const std::vector<SoakSample>& samples, double warmup_dive_h);

/// soak_rss.png and soak_cpu.png in `dir` (nothing with fewer than 2 samples).
void plot_soak(const std::vector<SoakSample>& samples, const SoakSummary& summary,
               const std::filesystem::path& dir);

}  // namespace nav::campaign
