#pragma once
// Test helpers for the survey simulator: simulate a dive into a per-process temporary
// directory, read truth.csv / images.csv back, and read the dive log's events and measurements.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/log/dive_log.h"
#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/sources/dive_log_source.h"
#include "nav/sim/simulate.h"

namespace nav::sim::test {

inline std::filesystem::path sim_config_path() {
  return std::filesystem::path(NAV_SOURCE_DIR) / "config" / "sim.yaml";
}

/// A fresh directory /tmp/nav_sim_test_<pid>/<name> (removed first if it exists).
inline std::filesystem::path scratch_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("nav_sim_test_" + std::to_string(::getpid())) / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// Simulator options writing the dive to `dir`, with `seed` and `images` (the rest default).
inline SimOptions sim_options(const std::filesystem::path& dir, std::uint64_t seed, int images) {
  SimOptions o;
  o.out_dir = dir.string();
  o.seed = seed;
  o.mission.images = images;
  return o;
}

/// The recovery of config/sim.yaml: a factor kept equal to Λ, its exact marginals renewed every
/// `refresh_interval` images and taken `renewal_lag` images later.
inline void use_kept_factor(daemon::NavdConfig& cfg, int refresh_interval, int renewal_lag = 0) {
  cfg.filter.recovery_preconditioner = core::RecoveryPreconditioner::kFactor;
  cfg.filter.recovery_keep_factor_equal = true;
  cfg.filter.recovery_refresh_interval = refresh_interval;
  cfg.filter.recovery_renewal_lag = renewal_lag;
}

/// Removes /tmp/nav_sim_test_<pid> at the end of the test program.
struct ScratchCleanup : ::testing::Environment {
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(
        std::filesystem::temp_directory_path() / ("nav_sim_test_" + std::to_string(::getpid())),
        ignored);
  }
};

inline std::string file_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Rows of a CSV file with a header line, as numbers.
inline std::vector<std::vector<double>> read_csv(const std::filesystem::path& p,
                                                 std::string* header = nullptr) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  if (header) *header = line;
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    std::vector<double> row;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) row.push_back(std::stod(cell));
    rows.push_back(std::move(row));
  }
  return rows;
}

/// truth.csv: t_us and the 12-element state.
struct TruthTable {
  std::int64_t t0_us = 0, step_us = 1;
  std::vector<core::Vec12> x;
  /// The state at a tick time (t on the tick grid, else the tick at or before t).
  const core::Vec12& at(std::int64_t t_us) const {
    std::int64_t k = (t_us - t0_us) / step_us;
    if (k < 0) k = 0;
    if (k >= static_cast<std::int64_t>(x.size())) k = static_cast<std::int64_t>(x.size()) - 1;
    return x[static_cast<std::size_t>(k)];
  }
};

inline TruthTable read_truth(const std::filesystem::path& dir) {
  TruthTable t;
  const auto rows = read_csv(dir / "truth.csv");
  t.t0_us = static_cast<std::int64_t>(rows.at(0)[0]);
  t.step_us = static_cast<std::int64_t>(rows.at(1)[0]) - t.t0_us;
  for (const auto& r : rows) {
    core::Vec12 x;
    for (int i = 0; i < 12; ++i) x[i] = r[static_cast<std::size_t>(i + 1)];
    t.x.push_back(x);
  }
  return t;
}

inline std::vector<daemon::DiveLogEvent> read_log(const std::filesystem::path& dir) {
  daemon::DiveLogReader reader((dir / "dive.lcmlog").string());
  std::vector<daemon::DiveLogEvent> events;
  while (auto e = reader.next()) events.push_back(std::move(*e));
  return events;
}

/// Every measurement of a dive log through the replay's dive-log source (decoders and clock
/// mappings of `cfg`), sorted by time of validity (ties in log order), none dropped.
inline std::vector<daemon::Measurement> time_ordered_measurements(const std::string& log,
                                                                  const daemon::NavdConfig& cfg) {
  daemon::MeasurementQueue queue(4096);
  std::atomic<bool> stop{false}, done{false};
  daemon::DiveLogSourceOptions options;
  options.as_fast_as_possible = true;
  std::thread source([&] { daemon::run_dive_log_source(log, cfg, options, queue, stop, done); });
  std::vector<daemon::Measurement> all;
  for (bool finished = false; !finished;) {
    finished = done.load();
    if (queue.pop_bulk(all, 4096) == 0 && !finished) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }
  source.join();
  queue.pop_bulk(all, queue.size());
  std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) {
    return daemon::validity_us(a) < daemon::validity_us(b);
  });
  return all;
}

}  // namespace nav::sim::test
