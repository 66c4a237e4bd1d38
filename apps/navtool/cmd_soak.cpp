// navtool soak: navd live for hours of dive data (docs/faults.md "Soak", library
// hil-tests/campaign, nav::campaign::run_soak): one simulated dive played back to back by the
// HIL player at --speed into one navd, its RSS, CPU, descriptors, queue depth, drops and late
// measurements sampled; writes OUT/soak.csv, soak.json, soak_rss.png, soak_cpu.png and prints
// the summary JSON on stdout. Exit 0 when navd stayed up, dropped nothing and its fitted RSS
// grew by less than --max-rss-growth-percent, else 1.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "nav/campaign/soak.h"
#include "navtool/commands.h"

namespace nav::tool {
namespace {
namespace fs = std::filesystem;

struct SoakArgs {
  campaign::SoakOptions options;
  std::string out, navd, config = "config/sim.yaml";
  double max_rss_growth_percent = 5.0;
};

void run_soak_command(SoakArgs& args) {
  campaign::SoakOptions& o = args.options;
  o.out_dir = args.out;
  o.sim_config = args.config;
  std::error_code ec;
  o.navd_path = args.navd.empty() ? fs::read_symlink("/proc/self/exe", ec).parent_path() / "navd"
                                  : fs::path(args.navd);
  if (!fs::exists(o.navd_path)) {
    throw CommandError("soak: navd not found at " + o.navd_path.string() + " (give --navd)", 2);
  }
  campaign::SoakSummary s;
  try {
    s = campaign::run_soak(o);
  } catch (const std::exception& e) {
    throw CommandError(std::string("soak: ") + e.what());
  }
  std::cout << campaign::soak_json(s).dump(2) << std::endl;
  std::fprintf(stderr,
               "soak: %.2f dive hours in %.0f s wall: RSS %+.2f %% (%.3f MiB per dive hour), "
               "CPU %.1f s per dive hour, %lld queue drops, %lld late measurements\n",
               s.dive_hours, s.wall_s, s.rss_growth_percent, s.rss_slope_mb_per_dive_h,
               s.cpu_s_per_dive_h, static_cast<long long>(s.queue_drops),
               static_cast<long long>(s.late_measurements));
  if (!s.navd_alive || s.queue_drops > 0 || s.rss_growth_percent >= args.max_rss_growth_percent) {
    throw CommandExit{1};
  }
}

void add_soak(CLI::App& app) {
  auto args = std::make_shared<SoakArgs>();
  CLI::App* cmd = app.add_subcommand(
      "soak",
      "Soak navd live: one simulated dive played back to back at --speed into one navd (no "
      "camera), RSS / CPU / descriptors / queue sampled (docs/faults.md \"Soak\").");
  cmd->add_option("--out", args->out, "output directory")->required();
  cmd->add_option("--navd", args->navd, "navd binary (default: beside navtool)");
  cmd->add_option("--config", args->config, "simulator config (default config/sim.yaml)");
  cmd->add_option("--images", args->options.dive_images, "images of the dive (default 90: 845 s)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--passes", args->options.passes, "times the dive is played (default 12)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--speed", args->options.speed, "x real time (default 20)")
      ->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--sample-period-s", args->options.sample_period_s, "wall s between samples")
      ->check(CLI::Range(0.1, 3600.0));
  cmd->add_option("--warmup-dive-h", args->options.warmup_dive_h,
                  "dive hours left out of the fits (default 0.25)")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_option("--max-rss-growth-percent", args->max_rss_growth_percent,
                  "fail above this fitted RSS growth (default 5)");
  cmd->add_option("--seed", args->options.seed, "seed of the dive (default 7)");
  cmd->callback([args] { run_soak_command(*args); });
}

const CommandRegistration kRegister{"soak", add_soak};

}  // namespace
}  // namespace nav::tool
