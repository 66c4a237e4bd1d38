// navtool survey [--config config/sim.yaml] [--as-fast-as-possible | --speed X] [--out DIR]
//                [--images N] [--seed S] [--vision] [--checkpoints] [--lcm-url URL]
// The simulated survey end to end: the dive of the config's `sim` section is simulated into
// sim.dive_dir when missing or simulated with other options (survey/survey_dive.h), replayed
// through navd's replay mode (nav/daemon/service/replay_mode.h: the same source, time ordering,
// NavFilter and LCM publishers as `navd --replay`), and with --out the replay output directory
// and the report (metrics.json, the paper's figures; report/report.h) are written there.
// --vision (or vision.enabled in the config): the whole visual pipeline: the dive is simulated
// with rendered frames and navd registers them itself (vision/vision_link.h) instead of
// reading the simulator's oracle. The replay's JSON summary goes to stdout; the last line on
// stderr says where the report is.
// LCM: the config's URL (config/sim.yaml: udpm with ttl=0); a host without a multicast route
// falls back to memq:// with a warning naming the fix, unless --lcm-url asked for the URL.
// SIGTERM/SIGINT stop the simulation or the replay (STOPPING=1); the report of a stopped replay
// covers what was replayed. Exit status: 0 done or stopped, 1 the simulation, replay or report
// failed, 2 bad options or configuration.
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/daemon/service/lcm_url.h"
#include "nav/daemon/service/replay_mode.h"
#include "nav/daemon/system/sd_notify.h"
#include "nav/daemon/system/stop_signals.h"
#include "nav/daemon/vision/vision_link.h"
#include "nav/report/report.h"
#include "navtool/commands.h"
#include "navtool/survey/survey_dive.h"

namespace nav::tool {
namespace {

struct SurveyArgs {
  std::string config_path = "config/sim.yaml";
  std::optional<int> images;         ///< overrides sim.images
  std::optional<std::int64_t> seed;  ///< overrides sim.seed
  bool vision = false;               ///< render the frames and register them in navd
  double speed = 1.0;
  bool as_fast_as_possible = false;
  std::string out_dir;  ///< replay outputs and report; none without it
  bool checkpoints = false;
  std::string lcm_url;  ///< overrides lcm.url; no memq fallback when given
  int time_of_use_every = -1;  ///< -1: about 100 checks over the dive (images / 100)
  bool time_of_use_markov_blanket = false;
};

/// The report of the replay output directory `out_dir` of the dive `dive_dir`.
void write_report(const std::string& out_dir, const std::string& dive_dir) {
  report::ReportOptions options;
  options.out_dir = out_dir;
  options.dive_dir = dive_dir;
  const auto start = std::chrono::steady_clock::now();
  nlohmann::json metrics;
  try {
    metrics = report::run_report(options);
  } catch (const std::exception& e) {
    throw CommandError("survey: report of " + out_dir + ": " + e.what());
  }
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::string files = "metrics.json";
  for (const auto& figure : metrics["figures"]) files += ", " + figure.get<std::string>();
  spdlog::info("navtool survey: report ({:.1f} s) in {}: {}", wall_s,
               std::filesystem::absolute(out_dir).lexically_normal().string(), files);
}

void run_survey(const SurveyArgs& args) {
  const sigset_t signals = daemon::block_stop_signals();
  spdlog::set_default_logger(spdlog::stderr_color_mt("navtool-survey"));
  daemon::NavdConfig config;
  daemon::SimDiveConfig sim;
  try {
    config = daemon::load_config_file(args.config_path);
    if (!config.sim) {
      throw daemon::ConfigError(args.config_path, "sim",
                                "no `sim` section: navtool survey needs the simulated dive's "
                                "dive_dir, seed and images (config/sim.yaml)");
    }
    if (args.vision || config.vision.enabled) daemon::vision::enable_vision_in_replay(config);
    // udpm (config/sim.yaml) on a host without a multicast route: memq with a warning, unless
    // the URL was asked for with --lcm-url (nav/daemon/service/lcm_url.h).
    config.lcm.url = daemon::service::usable_lcm_url(
        args.lcm_url.empty() ? config.lcm.url : args.lcm_url, args.lcm_url.empty());
  } catch (const daemon::ConfigError& e) {
    throw CommandError(std::string("survey: configuration: ") + e.what(), 2);
  } catch (const std::invalid_argument& e) {
    throw CommandError(std::string("survey: ") + e.what(), 2);
  }
  sim = *config.sim;
  if (args.images) sim.images = *args.images;
  if (args.seed) sim.seed = static_cast<int>(*args.seed);
  const daemon::SdNotifier notifier;
  std::optional<std::string> log;
  try {
    log = ensure_sim_dive(sim, config.vision.enabled, args.config_path, signals, notifier);
  } catch (const daemon::ConfigError& e) {
    throw CommandError(std::string("survey: configuration: ") + e.what(), 2);
  } catch (const std::invalid_argument& e) {
    throw CommandError(std::string("survey: simulating ") + sim.dive_dir + ": " + e.what(), 2);
  } catch (const std::exception& e) {
    throw CommandError(std::string("survey: simulating ") + sim.dive_dir + ": " + e.what());
  }
  if (!log) {
    spdlog::info("navtool survey: stopped during the simulation; nothing replayed");
    return;
  }
  const int time_of_use_every =
      args.time_of_use_every >= 0 ? args.time_of_use_every : std::max(1, sim.images / 100);
  const daemon::service::ReplayModeArgs replay{.log_path = *log,
                                               .config_path = args.config_path,
                                               .speed = args.speed,
                                               .as_fast_as_possible = args.as_fast_as_possible,
                                               .out_dir = args.out_dir,
                                               .checkpoints = args.checkpoints,
                                               .checkpoint_identity = sim_dive_identity(sim),
                                               .time_of_use_every_images = time_of_use_every,
                                               .time_of_use_markov_blanket =
                                                   args.time_of_use_markov_blanket};
  spdlog::info(
      "navtool survey: live view: `navtool topside --config {}` in another terminal, then open "
      "http://127.0.0.1:8765/ (or Foxglove Studio on ws://127.0.0.1:8765); pace the replay with "
      "--speed 20 to watch it",
      args.config_path);
  if (args.checkpoints) {
    spdlog::info("navtool survey: checkpoints in {} (input '{}')", config.checkpoint.path,
                 replay.checkpoint_identity);
  }
  if (const int status = daemon::service::run_replay_mode(config, replay, signals, notifier);
      status != 0) {
    throw CommandExit{status};  // the replay mode logged why and printed its summary
  }
  if (args.out_dir.empty()) {
    spdlog::info("navtool survey: no --out: no replay outputs and no report written");
    return;
  }
  write_report(args.out_dir, sim.dive_dir);
}

void add_survey(CLI::App& app) {
  auto args = std::make_shared<SurveyArgs>();
  CLI::App* cmd = app.add_subcommand(
      "survey",
      "The simulated survey end to end: simulate the config's `sim` dive (once; again when "
      "its options change), replay it through navd's replay mode publishing on LCM, and with "
      "--out write the replay outputs and the report (metrics.json, figures) there. The "
      "replay's JSON summary goes to stdout.");
  cmd->add_option("--config", args->config_path, "navd YAML configuration with a `sim` section")
      ->capture_default_str();
  cmd->add_option("--images", args->images, "images in the simulated dive (overrides sim.images)")
      ->check(CLI::Range(2, 100000));
  cmd->add_option("--seed", args->seed, "seed of the simulated dive (overrides sim.seed)")
      ->check(CLI::Range(std::int64_t{0}, std::int64_t{2147483647}));
  cmd->add_flag("--vision", args->vision,
                "the whole visual pipeline: simulate the dive with rendered frames and let "
                "navd register them (config vision.enabled; filter.registration_wait_s raised "
                "to 8 s if not above vision.answer_delay_s) instead of the simulator's oracle");
  auto* speed = cmd->add_option("--speed", args->speed, "replay speed, x real time")
                    ->check(CLI::PositiveNumber);
  cmd->add_flag("--as-fast-as-possible", args->as_fast_as_possible, "replay without pacing")
      ->excludes(speed);
  cmd->add_option("--out", args->out_dir, "write the replay outputs and the report here");
  cmd->add_flag("--checkpoints", args->checkpoints,
                "resume from the newest valid checkpoint of this dive in checkpoint.path and "
                "write checkpoints there (period_s, at the end)");
  cmd->add_option("--lcm-url", args->lcm_url,
                  "LCM URL (overrides lcm.url; no memq:// fallback when it cannot be opened)");
  add_time_of_use_options(*cmd, args->time_of_use_every, args->time_of_use_markov_blanket);
  cmd->callback([args] { run_survey(*args); });
}

const CommandRegistration kRegister{"survey", add_survey};

}  // namespace
}  // namespace nav::tool
