#pragma once
// The soak (docs/faults.md "Soak", `navtool soak`): one navd in live mode (--checkpoints) fed
// by the HIL player with one simulated dive played `passes` times back to back
// (PlayerOptions::repeat) at `speed` x real time, the camera not played (its schedule is one
// pass): hours of sensor data through the device threads, decoders, queue, filter, checkpoints
// and publisher of one process. Every `sample_period_s` (wall) it samples navd's VmRSS,
// CPU time (utime + stime of /proc/<pid>/stat), open descriptors (/proc/<pid>/fd) and, from
// NAVD_HEALTH, the queue depth, queue drops and late measurements summed over the sensors.
// At speed > 1 navd sees a dive `speed` times shorter (hil-tests/README.md "Speed"): the soak
// measures resources and drops, not the pose. Without images the map does not grow, so the
// RSS of a growing map is not what this measures.
// Outputs in out_dir: soak.csv (the samples), soak.json (the summary), soak_rss.png and
// soak_cpu.png (RSS and CPU seconds per dive hour against dive hours, with the fitted line).
//
// Threads: run_soak() enters a private network namespace first: call it before any thread.

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace nav::campaign {

struct SoakOptions {
  std::filesystem::path out_dir, navd_path, sim_config;
  int dive_images = 90;  ///< the dive played (90 images: 845 s, config/sim.yaml)
  int passes = 12;       ///< times the dive is played back to back
  double speed = 20.0;
  double sample_period_s = 5.0;  ///< wall seconds between samples
  double warmup_dive_h = 0.25;   ///< samples before this are left out of the fits
  std::uint64_t seed = 7;
  std::string lcm_url = "udpm://239.255.76.67:7673?ttl=0";
};

struct SoakSummary {
  double dive_hours = 0.0, wall_s = 0.0;
  int samples = 0;
  double rss_first_mb = 0.0, rss_last_mb = 0.0;  ///< fitted line at warm-up end / at the end
  double rss_slope_mb_per_dive_h = 0.0;
  double rss_growth_percent = 0.0;    ///< (last - first) / first of the fitted line
  double cpu_s_per_dive_h = 0.0;      ///< after warm-up
  double cpu_slope_per_dive_h = 0.0;  ///< of the per-interval CPU s / dive h, per dive hour
  int fds_min = 0, fds_max = 0;       ///< after warm-up
  int max_queue_depth = 0;
  std::int64_t queue_drops = 0, late_measurements = 0;  ///< at the end, every sensor
  bool navd_alive = false;                              ///< running when the playback ended
  int navd_exit_code = -1;
  std::string navd_summary;  ///< navd's JSON line at its stop
};

/// Runs the soak; throws std::runtime_error naming what failed (dive, navd, LCM).
SoakSummary run_soak(const SoakOptions& options);

nlohmann::json soak_json(const SoakSummary& summary);

}  // namespace nav::campaign
