#pragma once
// navtool report: reads a replay output directory (and the simulated dive it replayed) and
// writes metrics.json and the paper's figures into the replay output directory
// (Eustice et al., RSS 2005, Figs. 1, 2, 3, 5; formats in hil-tests/README.md "Report").

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "nav/report/figures.h"
#include "nav/report/metrics.h"

namespace nav::report {

struct ReportOptions {
  std::filesystem::path out_dir;                  ///< the replay output directory (read + written)
  std::optional<std::filesystem::path> dive_dir;  ///< default: summary.json "dive_dir" if present
  int histogram_bins = 20;                        ///< Fig. 3
  NetworkOptions network;                         ///< Fig. 5
  MetricsOptions metrics;
};

/// Runs the report; returns the metrics (also written to out_dir/metrics.json). Throws
/// ReportError on bad input (message names file:line) or when a file cannot be written.
nlohmann::json run_report(const ReportOptions& options);

/// The dive directory to use: the option, else summary.json "dive_dir" (absolute, relative to
/// the working directory, or relative to the replay output directory, first that exists).
std::optional<std::filesystem::path> resolve_dive_dir(const ReportOptions& options,
                                                      const daemon::ReplaySummary& summary);

}  // namespace nav::report
