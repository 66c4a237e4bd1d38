// navtool simulate: writes a simulated survey dive directory (hil-tests/README.md): the RMS
// Titanic-like survey of Eustice et al. (RSS 2005) with the sensors, mounts, noise and camera of
// a navd config, as the protocol bytes the instruments send (dive.lcmlog), plus truth.csv,
// images.csv, config.yaml and sim.json. Library: hil-tests/sim (nav::sim::simulate_dive).
// --json prints sim.json's content on stdout; a progress bar goes to stderr on a terminal.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/sim/simulate.h"
#include "navtool/commands.h"

namespace nav::tool {
namespace {

struct SimulateArgs {
  std::string out_dir;
  std::string config_path = "config/sim.yaml";
  std::uint64_t seed = 1;
  int images = 866;
  double outlier_rate = 0.05;
  bool json = false;
  bool render_images = false;
  bool sensor_biases = false;
};

void draw_progress(double fraction) {
  const int width = 40;
  const int filled = static_cast<int>(fraction * width + 0.5);
  std::fprintf(stderr, "\rsimulating [%s%s] %3d %%",
               std::string(static_cast<std::size_t>(filled), '#').c_str(),
               std::string(static_cast<std::size_t>(width - filled), ' ').c_str(),
               static_cast<int>(fraction * 100.0 + 0.5));
  if (fraction >= 1.0) std::fputc('\n', stderr);
  std::fflush(stderr);
}

void run_simulate(const SimulateArgs& args) {
  sim::SimOptions o;
  o.out_dir = args.out_dir;
  o.seed = args.seed;
  o.mission.images = args.images;
  o.oracle.outlier_rate = args.outlier_rate;
  o.render_images = args.render_images;
  if (args.sensor_biases) o.sensor_errors = sim::SensorErrorOptions::with_sensor_biases();
  if (::isatty(STDERR_FILENO)) o.progress = draw_progress;
  const auto start = std::chrono::steady_clock::now();
  sim::SimSummary s;
  try {
    s = sim::simulate_dive(o, args.config_path);
  } catch (const daemon::ConfigError& e) {
    throw CommandError(std::string("simulate: ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw CommandError(std::string("simulate: ") + e.what());
  } catch (const std::runtime_error& e) {
    throw CommandError(std::string("simulate: ") + e.what());
  }
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (args.json) std::cout << s.to_json().dump() << std::endl;
  std::fprintf(stderr,
               "navtool simulate: %s: %lld images, %.0f s dive, track %.0f m, hull %.0f m^2, "
               "%lld registrations (%lld succeeded, %lld outliers), %lld log events, %.1f s\n",
               args.out_dir.c_str(), static_cast<long long>(s.images), s.duration_s,
               s.track_length_m, s.survey_hull_area_m2, static_cast<long long>(s.registrations),
               static_cast<long long>(s.registrations_succeeded),
               static_cast<long long>(s.outliers_injected), static_cast<long long>(s.log_events),
               wall_s);
}

void add_simulate(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "Simulate a survey dive like the RMS Titanic survey of RSS 2005 and write it as a dive "
      "directory (dive.lcmlog with the instruments' protocol bytes, oracle registrations, "
      "truth.csv, images.csv, config.yaml, sim.json; hil-tests/README.md).");
  cmd->add_option("--out", args->out_dir, "dive directory to write (created)")->required();
  cmd->add_option("--config", args->config_path,
                  "navd config whose sensors drive the simulation (default config/sim.yaml)");
  cmd->add_option("--seed", args->seed, "random seed (default 1)");
  cmd->add_option("--images", args->images,
                  "images in the dive (default 866, the paper's); the mission scales with it")
      ->check(CLI::Range(2, 100000));
  cmd->add_option("--outlier-rate", args->outlier_rate,
                  "fraction of successful registrations that are outliers (default 0.05)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_flag("--render-images", args->render_images,
                "also render each frame (12-bit grey, strobe-lit height field) to "
                "DIR/images/<frame %06d>.png with a thumbnail in NAV_IMAGE (~0.3 s per frame)");
  cmd->add_flag("--sensor-biases", args->sensor_biases,
                "uncalibrated vehicle: DVL scale factor 0.1 %, heading bias 0.05 deg, roll/pitch "
                "bias 0.02 deg, depth bias 0.02 m (default 0: calibrated out before the dive)");
  cmd->add_flag("--json", args->json, "print sim.json's content on stdout");
  cmd->callback([args] { run_simulate(*args); });
}

const CommandRegistration kRegister{"simulate", add_simulate};

}  // namespace
}  // namespace nav::tool
