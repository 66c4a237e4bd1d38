#pragma once
// The fault campaign's measurements from what navd published (fault_campaign.h gives each
// number's definition): NEES and errors of NAVD_SOLUTION against truth.csv, the detection
// time from NAVD_HEALTH, the map's RMS error from NAVD_BOUNDS_SNAPSHOT.
//
// Threads: plain functions on data the listener collected.

#include <cstdint>
#include <filesystem>
#include <navlcm/bounds_snapshot_t.hpp>
#include <navlcm/health_t.hpp>
#include <navlcm/nav_solution_t.hpp>
#include <optional>
#include <vector>

#include "nav/campaign/fault_campaign.h"

namespace nav::campaign {

struct Recording {
  std::vector<navlcm::nav_solution_t> solutions;  ///< filter_status != 2 (initialised)
  std::vector<navlcm::health_t> health;
  std::vector<std::int64_t> health_received_us;  ///< the campaign's CLOCK_REALTIME at receipt
  std::optional<navlcm::bounds_snapshot_t> last_snapshot;
};

/// The player's dive-to-host mapping at speed 1: host monotonic h is dive time
/// dive_start_us + (h - host_start_us); `realtime_start_us` is CLOCK_REALTIME at host_start.
struct TimeMap {
  std::int64_t dive_start_us = 0, host_start_us = 0, realtime_start_us = 0;
  /// Dive seconds after the first played message of a host monotonic time.
  double dive_s(std::int64_t host_monotonic_us) const {
    return (host_monotonic_us - host_start_us) * 1e-6;
  }
  std::int64_t realtime_at(double dive_s) const {
    return realtime_start_us + static_cast<std::int64_t>(dive_s * 1e6);
  }
};

/// truth.csv: t_us (dive host time), x, y, z, roll, pitch, heading, ... at 20 Hz.
class TruthTrack {
 public:
  explicit TruthTrack(const std::filesystem::path& csv);
  /// x, y of the vehicle at dive host time `t_us`, linear between rows.
  std::pair<double, double> xy_at(double t_us) const;

 private:
  std::vector<std::vector<double>> rows_;
};

/// max_xy_error_m, nees_before/during/after, sigma_xy_start/end_m, solutions.
void fill_track_metrics(const Recording& rec, const TruthTrack& truth, const TimeMap& map,
                        const FaultScenario& scenario, ScenarioResult& out);

/// detected_after_s / detected_by: the first health message at or after `fault_realtime_us`
/// meeting the scenario's Detector (counters compared with the last message before it).
void fill_detection(const Recording& rec, std::int64_t fault_realtime_us,
                    const FaultScenario& scenario, ScenarioResult& out);

/// Of the newest health message received before `realtime_us` (the campaign's clock), the
/// sensor's counters; nullptr when there is none (or it lacks the sensor).
const navlcm::sensor_health_t* sensor_at(const Recording& rec, const std::string& sensor,
                                         std::int64_t realtime_us);

/// The health messages as CSV (utime, queue_depth, cpu_percent, rss_mb, then per sensor
/// connected, last_message_age_s, records, decode_errors, reconnects, rejected_updates,
/// nis_mean), the evidence behind detected_after_s. Throws std::runtime_error naming `path`.
void write_health_csv(const Recording& rec, const std::filesystem::path& path);

/// The solutions against the truth as CSV (dive_s, x_m, y_m, truth_x_m, truth_y_m, xy_error_m,
/// sigma_xy_m, nees_xy, delayed_states, filter_status): the evidence behind the NEES columns.
void write_solutions_csv(const Recording& rec, const TruthTrack& truth, const TimeMap& map,
                         const std::filesystem::path& path);

/// RMS horizontal error of the snapshot's delayed-state means against the truth at their image
/// times; -1 without a snapshot or states.
double map_xy_rms_m(const Recording& rec, const TruthTrack& truth, const TimeMap& map);

}  // namespace nav::campaign
