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

/// One set of Fig. 3 ratios: ours and the Markov blanket's (the pairs that have it).
struct Ratios {
  std::vector<double> ours, markov_blanket;
  bool every_pair_has_blanket() const { return markov_blanket.size() == ours.size(); }
};

Ratios ratios_at_end(const ReplayOutput& replay) {  // logdet.csv
  Ratios r;
  for (const auto& row : replay.logdet) {
    r.ours.push_back(row.ours);
    r.markov_blanket.push_back(row.markov_blanket);
  }
  return r;
}

Ratios ratios_at_time_of_use(const ReplayOutput& replay) {  // time_of_use.csv
  Ratios r;
  for (const TimeOfUseRow& row : replay.time_of_use) {
    r.ours.push_back(row.ours);
    if (!std::isnan(row.markov_blanket)) r.markov_blanket.push_back(row.markov_blanket);
  }
  return r;
}

/// The checks' counts and fractions (summary) and their ratios: null without checks.
void add_time_of_use(const daemon::ReplaySummary& s, const Ratios& at_use, json& m) {
  m["time_of_use_checks"] = s.time_of_use_checks;
  m["time_of_use_s"] = s.time_of_use_s;
  m["time_of_use_conservative_fraction"] = s.time_of_use_conservative_fraction;
  m["time_of_use_joint_conservative_fraction"] = s.time_of_use_joint_conservative_fraction;
  m["logdet_ratio_relative_ours"] = stats_json(at_use.ours);
  m["logdet_ratio_relative_markov_blanket"] = stats_json(at_use.markov_blanket);
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

  const Ratios at_end = ratios_at_end(replay), at_use = ratios_at_time_of_use(replay);
  m["logdet_ratio_ours"] = stats_json(at_end.ours);
  m["logdet_ratio_markov_blanket"] = stats_json(at_end.markov_blanket);
  add_time_of_use(replay.summary, at_use, m);
  // Fig. 3 at the time of use when every checked pair has the blanket's ratio, else at the end.
  const bool fig3_at_use = !at_use.ours.empty() && at_use.every_pair_has_blanket();
  const Ratios& fig3 = fig3_at_use ? at_use : at_end;
  const std::string fig3_when =
      fig3_at_use ? "at the time of use (" + std::to_string(replay.summary.time_of_use_checks) +
                        " checks)"
                  : "at the end of the dive";
  m["fig3_values"] = fig3.ours.empty() ? "none" : fig3_when;

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
  if (!fig3.ours.empty()) {
    save("fig3_logdet_histogram.png",
         logdet_histogram_figure(fig3.ours, fig3.markov_blanket, options.histogram_bins,
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
