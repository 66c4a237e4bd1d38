#include "navtool/survey/survey_dive.h"

#include <spdlog/spdlog.h>

#include <atomic>
#include <chrono>
#include <exception>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "nav/sim/simulate.h"

namespace nav::tool {
namespace {

namespace fs = std::filesystem;

struct SimulationStopped {};  ///< thrown from the progress callback on a stop signal

/// Why the cached dive in `dir` cannot be used ("" if it can): missing files or other options.
std::string cache_mismatch(const daemon::SimDiveConfig& sim, bool render_images,
                           const fs::path& dir) {
  if (!fs::exists(dir / "dive.lcmlog")) return (dir / "dive.lcmlog").string() + " missing";
  std::ifstream in(dir / "sim.json");
  if (!in) return (dir / "sim.json").string() + " missing (simulation not finished)";
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.contains("options")) {
    return (dir / "sim.json").string() + ": no options";
  }
  const nlohmann::json& o = j["options"];
  if (o.value("seed", -1LL) != sim.seed || o.value("images", -1LL) != sim.images ||
      o.value("outlier_rate", -1.0) != sim.outlier_rate) {
    return (dir / "sim.json").string() + ": simulated with seed " +
           o.value("seed", nlohmann::json()).dump() + ", images " +
           o.value("images", nlohmann::json()).dump() + ", outlier_rate " +
           o.value("outlier_rate", nlohmann::json()).dump() + ", not the config's";
  }
  if (render_images && !o.value("render_images", false)) {
    return (dir / "sim.json").string() +
           ": simulated without frames, which the vision stage needs";
  }
  return {};
}

/// Runs simulate_dive on a thread while this one watches the stop signals and the watchdog;
/// false if stopped.
bool simulate(const daemon::SimDiveConfig& sim, bool render_images,
              const std::string& config_path, const sigset_t& stop_signals,
              const daemon::SdNotifier& notifier) {
  sim::SimOptions options;
  options.out_dir = sim.dive_dir;
  options.seed = static_cast<std::uint64_t>(sim.seed);
  options.mission.images = sim.images;
  options.oracle.outlier_rate = sim.outlier_rate;
  options.render_images = render_images;
  std::atomic<bool> stop{false}, done{false};
  int last_tenth = -1;
  options.progress = [&](double fraction) {
    if (stop.load()) throw SimulationStopped{};
    if (const int tenth = static_cast<int>(fraction * 10.0); tenth > last_tenth) {
      last_tenth = tenth;
      spdlog::info("navtool survey: simulating {}: {} %", sim.dive_dir, 10 * tenth);
    }
  };
  std::exception_ptr failure;
  bool stopped = false;
  std::thread worker([&] {
    try {
      const sim::SimSummary s = sim::simulate_dive(options, config_path);
      spdlog::info("navtool survey: simulated {}: {} images, {:.0f} s dive, {} log events",
                   sim.dive_dir, s.images, s.duration_s, s.log_events);
    } catch (const SimulationStopped&) {
      stopped = true;
    } catch (...) {
      failure = std::current_exception();
    }
    done.store(true);
  });
  const timespec tick{0, 20'000'000};
  const auto period = notifier.watchdog_period();
  auto last_watchdog = std::chrono::steady_clock::now();
  while (!done.load()) {
    if (const int sig = sigtimedwait(&stop_signals, nullptr, &tick); sig > 0) {
      spdlog::info("navtool survey: signal {}, stopping the simulation", sig);
      stop.store(true);
    }
    if (period && std::chrono::steady_clock::now() - last_watchdog >= *period) {
      notifier.watchdog();
      last_watchdog = std::chrono::steady_clock::now();
    }
  }
  worker.join();
  if (failure) std::rethrow_exception(failure);
  return !stopped && !stop.load();
}

}  // namespace

std::string sim_dive_identity(const daemon::SimDiveConfig& sim) {
  return "sim " + fs::absolute(sim.dive_dir).lexically_normal().string() + " seed " +
         std::to_string(sim.seed) + " images " + std::to_string(sim.images) + " outlier_rate " +
         nlohmann::json(sim.outlier_rate).dump();
}

std::optional<std::string> ensure_sim_dive(const daemon::SimDiveConfig& sim, bool render_images,
                                           const std::string& config_path,
                                           const sigset_t& stop_signals,
                                           const daemon::SdNotifier& notifier) {
  const fs::path dir(sim.dive_dir);
  const std::string log_path = (dir / "dive.lcmlog").string();
  const std::string mismatch = cache_mismatch(sim, render_images, dir);
  if (mismatch.empty()) {
    spdlog::info("navtool survey: reusing the simulated dive {}", sim.dive_dir);
    return log_path;
  }
  spdlog::info("navtool survey: simulating the dive {} (seed {}, {} images{}): {}",
               sim.dive_dir, sim.seed, sim.images, render_images ? ", rendering the frames" : "",
               mismatch);
  notifier.status("simulating " + sim.dive_dir);
  fs::remove(dir / "sim.json");  // a dive interrupted from here on is never reused
  if (!simulate(sim, render_images, config_path, stop_signals, notifier)) return std::nullopt;
  return log_path;
}

}  // namespace nav::tool
