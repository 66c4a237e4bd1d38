// navtool report: the paper's figures (Eustice et al., RSS 2005, Figs. 1, 2, 3, 5) and a
// metrics JSON from a replay output directory and the simulated dive it replayed
// (daemon/src/report/, formats in hil-tests/README.md). Writes metrics.json and the PNGs into
// OUT_DIR; --json prints the metrics on stdout. Bad input: error naming file:line, exit 1.
#include <iostream>
#include <memory>

#include "navtool/commands.h"
#include "nav/report/csv_table.h"
#include "nav/report/report.h"

namespace nav::tool {
namespace {

struct ReportArgs {
  std::string out_dir;
  std::string dive_dir;
  bool json = false;
  report::ReportOptions options;
};

void print_summary(const nlohmann::json& m) {
  std::cerr << "report: " << m["figures"].size() << " figures and metrics.json written to "
            << m["inputs"]["replay_dir"].get<std::string>() << "\n";
  for (const char* key :
       {"images", "camera_links", "links_proposed", "links_accepted", "outliers_injected",
        "outliers_rejected", "dr_xy_rms_m", "slam_xy_rms_m", "slam_final_xy_error_m", "nees_mean",
        "nees_95_interval", "conservative_fraction", "wall_s", "realtime_factor"}) {
    std::cerr << "  " << key << ": " << m[key].dump() << "\n";
  }
}

void run_report(ReportArgs& args) {
  args.options.out_dir = args.out_dir;
  if (!args.dive_dir.empty()) args.options.dive_dir = args.dive_dir;
  nlohmann::json metrics;
  try {
    metrics = report::run_report(args.options);
  } catch (const report::ReportError& e) {
    throw CommandError(std::string("report: ") + e.what());
  }
  if (args.json) {
    std::cout << metrics.dump() << std::endl;
  } else {
    print_summary(metrics);
  }
}

void add_report(CLI::App& app) {
  auto args = std::make_shared<ReportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "report",
      "Metrics and the paper's figures (RSS 2005 Figs. 1, 2, 3, 5) from a replay output "
      "directory: writes metrics.json, fig1_trajectory.png, fig2_sparsity.png, "
      "fig3_logdet_histogram.png, fig5_network.png into OUT_DIR (see hil-tests/README.md "
      "\"Report\"). Truth-based metrics need the dive directory (--dive, else summary.json "
      "\"dive_dir\").");
  cmd->add_option("out_dir", args->out_dir, "replay output directory (read and written)")
      ->required();
  cmd->add_option("--dive", args->dive_dir, "the simulated dive directory (truth.csv, ...)");
  cmd->add_flag("--json", args->json, "print metrics.json on stdout (else a summary on stderr)");
  cmd->add_option("--bins", args->options.histogram_bins, "Fig. 3 histogram bins (default 20)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--ellipse-inflation", args->options.network.inflation,
                  "Fig. 5 ellipse inflation factor (default: automatic, stated in the figure)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--conservative-tolerance", args->options.metrics.conservative_tolerance,
                  "relative tolerance of the PSD check of bound - exact (default 1e-9)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([args] { run_report(*args); });
}

const CommandRegistration kRegister{"report", add_report};

}  // namespace
}  // namespace nav::tool
