#pragma once
// simulate_dive: the whole simulated survey written as a dive directory (hil-tests/README.md
// "A dive directory"): dive.lcmlog (RAW_<NAME> protocol bytes, NAV_IMAGE, NAV_REGISTRATION),
// config.yaml, truth.csv, images.csv, sim.json. Deterministic: the same options, config and
// seed give byte-identical files. `navtool simulate` is its command line; navd calls it to
// create the default dive when it is missing.

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/sim/mission.h"
#include "nav/sim/oracle.h"
#include "nav/sim/renderer.h"
#include "nav/sim/seafloor.h"
#include "nav/sim/sensor_streams.h"
#include "nav/sim/vehicle.h"

namespace nav::sim {

struct SimOptions {
  std::string out_dir;  ///< created if missing; existing dive files are overwritten
  std::uint64_t seed = 1;
  double tick_hz = 20.0;   ///< truth integration rate; a divisor of 20 ms steps: 20 or 40 Hz ...
  MissionOptions mission;  ///< mission.images: the number of images (default 866)
  VehicleOptions vehicle;
  SeafloorOptions seafloor;
  SensorErrorOptions sensor_errors;
  OracleOptions oracle;        ///< oracle.outlier_rate: --outlier-rate
  bool render_images = false;  ///< write images/<frame %06d>.png (renderer.h), thumbnails
  RenderOptions render;
  /// Called now and then with the fraction of the dive simulated, in [0, 1].
  std::function<void(double)> progress;
};

/// The counts written to sim.json (hil-tests/README.md) and printed by `navtool simulate --json`.
struct SimSummary {
  std::int64_t images = 0;
  std::int64_t registrations = 0;
  std::int64_t registrations_succeeded = 0;
  std::int64_t outliers_injected = 0;
  double track_length_m = 0.0;       ///< 3-D path length of the whole dive
  double survey_hull_area_m2 = 0.0;  ///< convex hull of the track while the camera is on
  double duration_s = 0.0;
  std::int64_t truth_samples = 0;
  std::int64_t log_events = 0;
  double min_altitude_m = 0.0, mean_altitude_m = 0.0, max_altitude_m = 0.0;  ///< at the images
  double max_time_gap_between_images_s = 0.0;  ///< the camera-off transit
  std::int64_t first_frame_after_transit = -1;
  SensorCounts sensors;
  std::int64_t degenerate_pairs_skipped = 0;
  nlohmann::json options;          ///< what sim.json records under "options"
  nlohmann::json to_json() const;  ///< sim.json's content
};

/// Simulates the dive with the sensors of `config` and writes it to options.out_dir; the
/// config file's text `config_yaml` is copied to config.yaml. Throws std::invalid_argument on
/// bad options or a config without the needed sensor types, std::runtime_error on I/O errors
/// (naming the file).
SimSummary simulate_dive(const SimOptions& options, const daemon::NavdConfig& config,
                         const std::string& config_yaml);

/// Loads `config_path` (daemon::load_config_file, ConfigError on a bad file) and simulates.
SimSummary simulate_dive(const SimOptions& options, const std::string& config_path);

}  // namespace nav::sim
