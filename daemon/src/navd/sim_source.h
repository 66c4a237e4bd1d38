#pragma once
// The "sim" source thread: replays a simulated survey (core/sim/survey.h) as timestamped
// measurements into the MeasurementQueue, like a driver thread would.
//
// Time base: survey time, t = 0 at the start of step 0; step k starts at start_us(k) and its
// navigation measurements are valid at end_us(k) = start_us(k + 1). An image at the start of
// step k is an ImageEvent valid at start_us(k) with frame_id = image index.
// Measurements (survey models, body frame: the simulator measures the vehicle directly, so the
// sim sensors' mounts are not applied): DvlVelocity = step.dvl, Attitude = (attitude[0],
// attitude[1], heading[0]), Depth = step.depth[0].
// Pacing: at `speed` x real time, or as fast as possible; in the latter mode the source waits
// while the queue is more than half full (a simulator may throttle; a real driver would drop).

#include <atomic>
#include <cstdint>
#include <vector>

#include "nav/core/sim/survey.h"
#include "nav/daemon/config.h"
#include "nav/daemon/measurement_queue.h"

namespace nav::navd {

/// Sensor indices (into NavdConfig::sensors) the simulated measurements are attributed to;
/// -1 when the config has no such sensor (that measurement is then not produced).
struct SimSensorIndices {
  int dvl = -1, attitude = -1, depth = -1, camera = -1;
};
SimSensorIndices find_sim_sensors(const daemon::NavdConfig& config);

/// Step start times in microseconds (size steps + 1; the last is the survey's end).
std::vector<std::int64_t> step_start_times_us(const core::sim::Survey& survey);

struct SimSourceOptions {
  double speed = 1.0;  ///< x real time (> 0); ignored when as_fast_as_possible
  bool as_fast_as_possible = false;
};

/// Runs on its own thread; returns at the end of the survey or when `stop` is set. Sets `done`
/// after the last push.
void run_sim_source(const core::sim::Survey& survey, const SimSensorIndices& sensors,
                    const SimSourceOptions& options, daemon::MeasurementQueue& queue,
                    const std::atomic<bool>& stop, std::atomic<bool>& done);

/// CLOCK_MONOTONIC / CLOCK_REALTIME in microseconds.
std::int64_t monotonic_us();
std::int64_t realtime_us();

}  // namespace nav::navd
