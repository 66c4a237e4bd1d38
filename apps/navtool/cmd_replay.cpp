// navtool replay DIVE_DIR_OR_LOG [--config C] [--speed X | --as-fast-as-possible] [--out DIR]
// [--json]: plays a recorded dive (hil-tests/README.md) through the same decoders, time ordering
// and NavFilter as navd (replay/dive_replay.h), with dead reckoning beside it, and prints a
// JSON summary; --out writes the replay output directory (summary.json, trajectory.csv,
// dead_reckoning.csv, states.csv, links.csv, proposals.csv, information_blocks.csv,
// logdet.csv). Recovery: the configured fixed PCG iterations at each image, synchronously or
// on NavFilter's recovery thread (filter.recovery_thread) taken at data times (nav_filter.h),
// so the output does not depend on timing. Default config:
// DIVE/config.yaml. --vision: navd registers the dive's rendered frames itself (vision.enabled,
// nav/daemon/vision/vision_link.h) instead of reading the log's registrations.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/daemon/log/dive_log.h"
#include "nav/daemon/replay/dive_replay.h"
#include "nav/daemon/replay/replay_summary.h"
#include "nav/daemon/vision/vision_link.h"
#include "nav/report/metrics.h"
#include "nav/report/replay_data.h"
#include "navtool/commands.h"

namespace nav::tool {
namespace {

struct ReplayArgs {
  std::string input;
  std::string config_path;
  double speed = 1.0;
  bool as_fast_as_possible = false;
  std::string out_dir;
  bool json = false;
  bool vision = false;
  int time_of_use_every = 0;
  bool time_of_use_markov_blanket = false;
};

/// vision_answers.csv: every answer of navd's vision stage applied in the replay, in proposal
/// order: frame_i, frame_j, success, applied_us (data time), z0..z4 (CameraRelativePoseModel
/// order), c00..c44 (5x5 covariance row-major), inliers and max_leverage (of registrations that
/// got as far as the refinement, else 0), reason (quoted; "" on success).
void write_vision_answers(const daemon::ReplayRun& run, const std::filesystem::path& path) {
  std::ofstream out(path);
  out << "frame_i,frame_j,success,applied_us";
  for (int k = 0; k < 5; ++k) out << ",z" << k;
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 5; ++c) out << ",c" << r << c;
  out << ",inliers,max_leverage,reason\n";
  out.precision(17);
  for (const daemon::vision::AppliedAnswer& a : run.vision_answers) {
    const core::Registration& g = a.registration;
    out << g.frame_id_i << ',' << g.frame_id_j << ',' << (g.success ? 1 : 0) << ','
        << g.available_us;
    for (int k = 0; k < 5; ++k) out << ',' << g.z(k);
    for (int r = 0; r < 5; ++r)
      for (int c = 0; c < 5; ++c) out << ',' << g.covariance(r, c);
    out << ',' << a.inliers << ',' << a.max_leverage;
    std::string reason = a.reason;
    for (char& ch : reason) {
      if (ch == '"') ch = '\'';
    }
    out << ",\"" << reason << "\"\n";
  }
  if (!out) throw CommandError("replay: cannot write " + path.string());
}

void run_replay_command(const ReplayArgs& args) {
  namespace fs = std::filesystem;
  const fs::path input(args.input);
  const bool is_dir = fs::is_directory(input);
  const fs::path log = is_dir ? input / "dive.lcmlog" : input;
  const fs::path dive_dir = is_dir ? input : input.parent_path();
  const fs::path config_path = args.config_path.empty() ? dive_dir / "config.yaml"
                                                        : fs::path(args.config_path);
  if (!fs::exists(log)) throw CommandError("replay: no dive log at " + log.string());
  try {
    daemon::NavdConfig config = daemon::load_config_file(config_path.string());
    if (args.vision) daemon::vision::enable_vision_in_replay(config);
    daemon::ReplayOptions options;
    options.speed = args.speed;
    options.as_fast_as_possible = args.as_fast_as_possible;
    options.time_of_use_every_images = args.time_of_use_every;
    options.time_of_use_markov_blanket = args.time_of_use_markov_blanket;
    daemon::ReplayRun run = daemon::run_replay(log.string(), config, options);
    const daemon::ReplayAnalysis analysis = daemon::analyse(*run.slam);
    daemon::ReplaySummary brief =
        daemon::make_replay_summary(run, analysis, dive_dir.string(), config_path.string());
    if (const fs::path truth = dive_dir / "truth.csv"; fs::exists(truth)) {
      // The published covariance against the simulator's truth (report::published_nees).
      const report::PublishedNees nees =
          report::published_nees(run.published, report::read_timed_poses(truth));
      if (nees.samples > 0) {
        brief.published_nees_mean = nees.mean;
        brief.published_nees_exceed_99_fraction = nees.exceed_99_fraction;
      }
    }
    const std::string summary = daemon::replay_summary_json(brief, run);
    if (!args.out_dir.empty()) {
      daemon::write_replay_outputs(run, analysis, summary, args.out_dir);
      if (run.vision) write_vision_answers(run, fs::path(args.out_dir) / "vision_answers.csv");
    }
    if (args.json) {
      std::cout << summary << std::endl;
    } else {
      std::cerr << summary << std::endl;
    }
    if (!run.error.empty()) throw CommandError("replay: " + run.error);
  } catch (const daemon::ConfigError& e) {
    throw CommandError(std::string("replay: config: ") + e.what());
  } catch (const daemon::DiveLogError& e) {
    throw CommandError(std::string("replay: ") + e.what());
  } catch (const std::runtime_error& e) {
    throw CommandError(std::string("replay: ") + e.what());
  }
}

}  // namespace

void add_time_of_use_options(CLI::App& cmd, int& every_images, bool& markov_blanket) {
  cmd.add_option("--time-of-use-every", every_images,
                 "check the bounds at the time of use at every K-th image (0: never), right "
                 "before its link proposal: every bound and proposal joint against the exact "
                 "marginals of that moment, and Fig. 3's relative-pose log-det ratio "
                 "(time_of_use.csv, summary keys time_of_use_*, logdet_ratio_relative_*). "
                 "Costs exact marginals of the whole map per check, kept off wall_s")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  cmd.add_flag("--time-of-use-markov-blanket", markov_blanket,
               "the time-of-use checks include the Markov blanket's ratios (about 3x slower)");
}

namespace {

void add_replay(CLI::App& app) {
  auto args = std::make_shared<ReplayArgs>();
  CLI::App* cmd = app.add_subcommand(
      "replay",
      "Replay a dive directory or dive.lcmlog through navd's decoders, time ordering and filter "
      "(ESDF, link proposal from the Algorithm 1 bounds, registration look-up, 5-dof gate), "
      "plus dead reckoning; JSON summary, --out writes the replay output files "
      "(hil-tests/README.md). Recovery: fixed PCG iterations (filter.cg_iterations_per_step) "
      "synchronously at each image, or on the recovery thread (filter.recovery_thread: true) "
      "taken at a data time (filter.recovery_handoff_s after each image); deterministic.");
  cmd->add_option("dive", args->input, "dive directory (with dive.lcmlog) or a .lcmlog file")
      ->required();
  cmd->add_option("--config", args->config_path, "navd config (default DIVE/config.yaml)");
  auto* speed = cmd->add_option("--speed", args->speed, "x real time on the log's clock")
                    ->check(CLI::PositiveNumber);
  cmd->add_flag("--as-fast-as-possible", args->as_fast_as_possible, "no pacing")->excludes(speed);
  cmd->add_option("--out", args->out_dir, "write the replay output directory here");
  cmd->add_flag("--json", args->json, "summary on stdout (else on stderr)");
  cmd->add_flag("--vision", args->vision,
                "register the dive's frames (DIVE/images, navtool simulate --render-images) with "
                "navd's vision stage instead of reading the log's registrations (config "
                "vision.enabled; filter.registration_wait_s raised to 8 s if not above "
                "vision.answer_delay_s); deterministic");
  add_time_of_use_options(*cmd, args->time_of_use_every, args->time_of_use_markov_blanket);
  cmd->callback([args] { run_replay_command(*args); });
}

const CommandRegistration kRegister{"replay", add_replay};

}  // namespace
}  // namespace nav::tool
