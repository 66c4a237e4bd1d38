#pragma once
// The report figures after Eustice et al., RSS 2005 (paper figure numbers), drawn with Plot:
//   Fig. 1 trajectory (XY of dead reckoning, SLAM and truth),
//   Fig. 2 sparsity pattern of the final information matrix,
//   Fig. 3 histogram of log(det approx / det exact), ours vs the Markov blanket,
//   Fig. 5 pose-constraint network with 3-sigma XY ellipses (initial bound, current bound,
//          exact marginal), inflated for visibility.
// Maps are drawn with East (y_m) to the right and North (x_m) up (world NED seen from above).

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "nav/report/plot.h"
#include "nav/report/replay_data.h"

namespace nav::report {

/// Fig. 1. `truth` may be empty (no dive directory); `subtitle` e.g. the RMS errors.
cv::Mat trajectory_figure(const std::vector<TimedPose>& dead_reckoning,
                          const std::vector<TimedPose>& slam, const std::vector<TimedPose>& truth,
                          const std::string& subtitle, const PlotStyle& style = {});

/// Size and fill of the information matrix from its block pattern: every listed block counts
/// as a dense D x D block, off-diagonal blocks twice (Λ is symmetric; the file lists i <= j).
struct Sparsity {
  long long dim = 0;       ///< D * num_blocks
  long long nonzeros = 0;  ///< D^2 (diagonal blocks + 2 off-diagonal blocks)
  double nonzero_fraction = 0.0;
};
Sparsity sparsity_of(const BlockPattern& pattern);

/// Fig. 2. Title states the dimension and % non-zero.
cv::Mat sparsity_figure(const BlockPattern& pattern, const PlotStyle& style = {});

/// Fig. 3: histograms with common bins of `ours` and `markov_blanket` (either may be empty,
/// not both), zero line dashed (positive = conservative). Throws ReportError when both are empty.
cv::Mat logdet_histogram_figure(const std::vector<double>& ours,
                                const std::vector<double>& markov_blanket, int bins,
                                const std::string& title, const PlotStyle& style = {});

struct NetworkOptions {
  double sigmas = 3.0;     ///< ellipse radius in standard deviations
  double inflation = 0.0;  ///< ellipse inflation; 0 = automatic (stated in the figure)
  int max_ellipses = 300;  ///< draw every k-th state's ellipses above this many states
};
/// The automatic inflation: a 1-2-5 number >= 1 that makes the median current-bound ellipse
/// about 1.5 % of the map's larger extent.
double automatic_inflation(const std::vector<DelayedState>& states, double sigmas);

/// Fig. 5. Temporal links join consecutive state ids; spatial links are the accepted rows of
/// links.csv (states looked up by state id; pairs naming unknown states are skipped).
cv::Mat network_figure(const std::vector<DelayedState>& states,
                       const std::vector<ProposedLink>& links, const NetworkOptions& options,
                       const PlotStyle& style = {});

}  // namespace nav::report
