// run_report: see report.h.
#include "nav/report/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "nav/core/recovery/consistency.h"
#include "nav/daemon/replay/output_schema.h"
#include "nav/report/csv_table.h"

namespace nav::report {
namespace fs = std::filesystem;
using nlohmann::json;
namespace {

std::string fmt(const char* format, double v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

json stats_json(const std::vector<double>& v) {
  if (v.empty()) return nullptr;
  const core::SummaryStats s = core::summarize(v);
  const auto nonneg = std::count_if(v.begin(), v.end(), [](double x) { return x >= 0.0; });
  return {{"min", s.min},
          {"median", s.median},
          {"max", s.max},
          {"count", s.count},
          {"nonnegative_fraction", static_cast<double>(nonneg) / static_cast<double>(v.size())}};
}

/// Reference numbers of the paper (RSS 2005, Sec. V) for the side-by-side comparison.
json paper_reference() {
  return {{"images", 866},
          {"states", 867},
          {"state_dim", 12},
          {"information_matrix_dim", 10404},
          {"information_matrix_nonzero_percent", 0.52},
          {"camera_links", 3494},
          {"track_length_m", 3100}};
}

std::string trajectory_subtitle(const json& m) {
  if (m["dr_xy_rms_m"].is_null()) return "no dive directory: truth not drawn";
  return "XY RMS vs truth: dead reckoning " + fmt("%.3g", m["dr_xy_rms_m"].get<double>()) +
         " m, SLAM " + fmt("%.3g", m["slam_xy_rms_m"].get<double>()) + " m; final SLAM error " +
         fmt("%.3g", m["slam_final_xy_error_m"].get<double>()) + " m";
}

/// Fig. 3's ratios at the time of use (time_of_use.csv) and the checks' fractions (summary):
/// null without checks.
void add_time_of_use(const ReplayOutput& replay, json& m) {
  std::vector<double> ours, mb;
  for (const TimeOfUseRow& r : replay.time_of_use) {
    ours.push_back(r.ours);
    if (!std::isnan(r.markov_blanket)) mb.push_back(r.markov_blanket);
  }
  const daemon::ReplaySummary& s = replay.summary;
  m["time_of_use_checks"] = s.time_of_use_checks;
  m["time_of_use_s"] = s.time_of_use_s;
  m["time_of_use_conservative_fraction"] = s.time_of_use_conservative_fraction;
  m["time_of_use_joint_conservative_fraction"] = s.time_of_use_joint_conservative_fraction;
  m["logdet_ratio_relative_ours"] = stats_json(ours);
  m["logdet_ratio_relative_markov_blanket"] = stats_json(mb);
}

/// Fig. 3 from the time-of-use checks when every one carries the Markov blanket's ratio, else
/// from the end of the dive (logdet.csv). Empty `ours`: neither.
std::string fig3_values(const ReplayOutput& replay, std::vector<double>& ours,
                        std::vector<double>& mb) {
  const bool with_blanket =
      !replay.time_of_use.empty() &&
      std::none_of(replay.time_of_use.begin(), replay.time_of_use.end(),
                   [](const TimeOfUseRow& r) { return std::isnan(r.markov_blanket); });
  if (with_blanket) {
    for (const TimeOfUseRow& r : replay.time_of_use) {
      ours.push_back(r.ours);
      mb.push_back(r.markov_blanket);
    }
    return "at the time of use (" + std::to_string(replay.summary.time_of_use_checks) +
           " checks)";
  }
  for (const auto& r : replay.logdet) {
    ours.push_back(r.ours);
    mb.push_back(r.markov_blanket);
  }
  return "at the end of the dive";
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  if (!out) throw ReportError(path.string() + ": cannot write");
}

}  // namespace

std::optional<fs::path> resolve_dive_dir(const ReportOptions& options,
                                         const daemon::ReplaySummary& summary) {
  if (options.dive_dir) return options.dive_dir;
  if (!summary.dive_dir) return std::nullopt;
  const fs::path recorded = *summary.dive_dir;
  if (recorded.is_absolute() || fs::is_directory(recorded)) return recorded;
  if (fs::is_directory(options.out_dir / recorded)) return options.out_dir / recorded;
  throw ReportError((options.out_dir / daemon::output_schema::kSummaryFile).string() +
                    ": dive_dir '" + recorded.string() + "' not found (give --dive)");
}

json run_report(const ReportOptions& options) {
  const ReplayOutput replay = read_replay_output(options.out_dir);
  const std::optional<fs::path> dive_dir = resolve_dive_dir(options, replay.summary);
  std::optional<DiveData> dive;
  if (dive_dir) dive = read_dive(*dive_dir);

  json m = compute_metrics(replay, dive ? &*dive : nullptr, options.metrics);
  m["inputs"] = {{"replay_dir", options.out_dir.string()},
                 {"dive_dir", dive_dir ? json(dive_dir->string()) : json(nullptr)}};

  std::vector<double> end_ours, end_mb;
  for (const auto& r : replay.logdet) {
    end_ours.push_back(r.ours);
    end_mb.push_back(r.markov_blanket);
  }
  m["logdet_ratio_ours"] = stats_json(end_ours);
  m["logdet_ratio_markov_blanket"] = stats_json(end_mb);
  add_time_of_use(replay, m);
  std::vector<double> ours, mb;
  const std::string fig3_when = fig3_values(replay, ours, mb);
  m["fig3_values"] = ours.empty() ? "none" : fig3_when;

  json figures = json::array(), skipped = json::object();
  auto save = [&](const char* name, const cv::Mat& image) {
    write_png((options.out_dir / name).string(), image);
    figures.push_back(name);
  };
  save("fig1_trajectory.png",
       trajectory_figure(replay.dead_reckoning, replay.trajectory,
                         dive ? dive->truth : std::vector<TimedPose>{}, trajectory_subtitle(m)));
  if (replay.blocks) {
    const Sparsity s = sparsity_of(*replay.blocks);
    m["information_matrix"] = {{"dim", s.dim},
                               {"block_dim", replay.blocks->block_dim},
                               {"blocks", replay.blocks->num_blocks},
                               {"nonzero_blocks", replay.blocks->blocks.size()},
                               {"nonzero_fraction", s.nonzero_fraction}};
    save("fig2_sparsity.png", sparsity_figure(*replay.blocks));
  } else {
    skipped["fig2_sparsity.png"] = "information_blocks.csv absent";
  }
  if (!ours.empty()) {
    save("fig3_logdet_histogram.png",
         logdet_histogram_figure(ours, mb, options.histogram_bins,
                                 "Fig. 3  Relative-pose log det ratio to exact, " +
                                     fig3_when));
  } else {
    skipped["fig3_logdet_histogram.png"] = "logdet.csv and time_of_use.csv absent or empty";
  }
  if (!replay.states.empty()) {
    NetworkOptions net = options.network;
    if (!(net.inflation > 0.0)) net.inflation = automatic_inflation(replay.states, net.sigmas);
    m["fig5_ellipse_inflation"] = net.inflation;
    m["fig5_initial_bound_present"] = replay.states.front().initial.has_value();
    save("fig5_network.png", network_figure(replay.states, replay.links, net));
  } else {
    skipped["fig5_network.png"] = "states.csv has no rows";
  }
  m["figures"] = figures;
  m["figures_skipped"] = skipped;
  m["paper_rss2005"] = paper_reference();
  write_text(options.out_dir / "metrics.json", m.dump(2) + "\n");
  return m;
}

}  // namespace nav::report
