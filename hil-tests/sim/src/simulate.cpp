#include "nav/sim/simulate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>

#include "dive_files.h"
#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"
#include "nav/daemon/log/dive_log.h"
#include "nav/sim/geometry2d.h"
#include "nav/sim/renderer.h"

namespace nav::sim {
namespace {

namespace fs = std::filesystem;

const daemon::SensorConfig& camera_sensor(const daemon::NavdConfig& config) {
  for (const daemon::SensorConfig& s : config.sensors)
    if (daemon::is_camera(s.type)) return s;
  throw std::invalid_argument(
      "simulator: the config has no camera sensor (camera_gige or camera_v4l2)");
}

nlohmann::json options_json(const SimOptions& o, const daemon::NavdConfig& config) {
  const SensorErrorOptions& e = o.sensor_errors;
  const OracleOptions& r = o.oracle;
  constexpr double deg = 180.0 / std::numbers::pi;
  nlohmann::json sensors = nlohmann::json::array();
  for (const daemon::SensorConfig& s : config.sensors) sensors.push_back(s.name);
  return {
      {"seed", o.seed},
      {"images", o.mission.images},
      {"outlier_rate", r.outlier_rate},
      {"render_images", o.render_images},
      {"tick_hz", o.tick_hz},
      {"image_period_s", o.mission.image_period_s},
      {"speed_mps", o.mission.speed_mps},
      {"line_length_m", o.mission.line_length_m},
      {"line_spacing_m", o.mission.line_spacing_m},
      {"altitude_m", o.mission.altitude_m},
      {"seafloor_depth_m", o.seafloor.mean_depth_m},
      {"seafloor_resolution_m", o.seafloor.resolution_m},
      {"dvl_scale_error", e.dvl_scale_error},
      {"heading_bias_deg", e.heading_bias_rad * deg},
      {"roll_pitch_bias_deg", e.roll_pitch_bias_rad * deg},
      {"depth_bias_m", e.depth_bias_m},
      {"altitude_bias_m", e.altitude_bias_m},
      {"dvl_clock_offset_s", e.dvl_clock_offset_s},
      {"dvl_clock_drift_ppm", e.dvl_clock_drift_ppm},
      {"dvl_dropouts_per_hour", e.dvl_dropouts_per_hour},
      {"jitter_ms", e.jitter_ms},
      {"registration_sigma_deg",
       {r.azimuth_sigma_rad * deg, r.elevation_sigma_rad * deg, r.rotation_sigma_rad * deg,
        r.rotation_sigma_rad * deg, r.rotation_sigma_rad * deg}},
      {"sensors", sensors},
  };
}

/// Surge command: slow down while turning and while the depth error is large.
double surge_command(const SimOptions& o, double heading_error_rad, double depth_error_m) {
  const double turn = std::max(0.1, std::cos(std::min(std::abs(heading_error_rad), 1.5)));
  const double climb = std::clamp(1.0 - std::abs(depth_error_m) / 3.0, 0.2, 1.0);
  return o.mission.speed_mps * turn * turn * climb;
}

}  // namespace

nlohmann::json SimSummary::to_json() const {
  return {
      {"images", images},
      {"registrations", registrations},
      {"registrations_succeeded", registrations_succeeded},
      {"outliers_injected", outliers_injected},
      {"track_length_m", track_length_m},
      {"survey_hull_area_m2", survey_hull_area_m2},
      {"duration_s", duration_s},
      {"truth_samples", truth_samples},
      {"log_events", log_events},
      {"min_altitude_m", min_altitude_m},
      {"mean_altitude_m", mean_altitude_m},
      {"max_altitude_m", max_altitude_m},
      {"max_time_gap_between_images_s", max_time_gap_between_images_s},
      {"first_frame_after_transit", first_frame_after_transit},
      {"degenerate_pairs_skipped", degenerate_pairs_skipped},
      {"dvl_ensembles", sensors.dvl_ensembles},
      {"dvl_invalid_ensembles", sensors.dvl_invalid_ensembles},
      {"heading_sentences", sensors.heading_sentences},
      {"attitude_sentences", sensors.attitude_sentences},
      {"depth_replies", sensors.depth_replies},
      {"altimeter_lines", sensors.altimeter_lines},
      {"options", options},
  };
}

SimSummary simulate_dive(const SimOptions& o, const daemon::NavdConfig& config,
                         const std::string& config_yaml) {
  if (!(o.tick_hz >= 10.0 && o.tick_hz <= 1000.0) || std::fmod(1e6 / o.tick_hz, 1.0) != 0.0 ||
      50000 % static_cast<std::int64_t>(1e6 / o.tick_hz) != 0)
    throw std::invalid_argument(
        "SimOptions.tick_hz: " + std::to_string(o.tick_hz) +
        " must give a whole number of µs dividing 50 ms (20, 40, 100 Hz ...)");
  if (const std::string e = o.oracle.validate(); !e.empty())
    throw std::invalid_argument("SimOptions.oracle." + e);
  if (const std::string e = o.sensor_errors.validate(); !e.empty())
    throw std::invalid_argument("SimOptions.sensor_errors." + e);
  if (o.out_dir.empty()) throw std::invalid_argument("SimOptions.out_dir: empty");

  const Mission mission = plan_mission(o.mission);
  const Seafloor seafloor(mission.extent, mission.wreck_x_m, mission.wreck_y_m, o.seafloor,
                          derive_seed(o.seed, 1));
  const double expected_s = 1.15 * o.mission.images * o.mission.image_period_s;
  SensorStreams sensors(config, o.sensor_errors, seafloor, expected_s, o.seed);
  const daemon::SensorConfig& camera_cfg = camera_sensor(config);
  const CameraGeometry camera = CameraGeometry::from_config(camera_cfg);
  RegistrationOracle oracle(camera, o.oracle, derive_seed(o.seed, 2));
  const Renderer renderer(camera, seafloor, o.render, derive_seed(o.seed, 5));

  fs::create_directories(o.out_dir);
  const fs::path dir(o.out_dir);
  DiveFiles files(dir, config_yaml);
  if (o.render_images) fs::create_directories(dir / "images");

  Guidance guidance(mission);
  const double z0 = seafloor.safe_depth_m(0.0, 0.0) - o.mission.altitude_m;
  Vehicle vehicle(core::Vec3(0.0, 0.0, z0), std::numbers::pi / 2.0, o.mission.speed_mps, o.vehicle,
                  derive_seed(o.seed, 3));
  std::mt19937_64 camera_rng(derive_seed(o.seed, 4));

  SimSummary sum;
  sum.options = options_json(o, config);
  const std::int64_t tick_us = static_cast<std::int64_t>(std::llround(1e6 / o.tick_hz));
  const std::int64_t image_period_us = std::llround(o.mission.image_period_s * 1e6);
  const double dt_s = tick_us * 1e-6;
  std::vector<Point2> imaging_track;
  std::int64_t last_image_us = -1, end_us = -1;
  double altitude_sum = 0.0;
  bool camera_was_off = false;  // since the last image
  core::Vec3 last_p(0.0, 0.0, z0);
  int last_progress = -1;
  sum.min_altitude_m = 1e9;
  for (std::int64_t k = 0;; ++k) {
    const std::int64_t t_us = kDiveStartMonotonicUs + k * tick_us;
    if (end_us >= 0 && t_us > end_us) break;
    const core::Vec12 x = vehicle.state();
    files.truth(t_us, x);
    ++sum.truth_samples;
    sum.track_length_m += (x.head<3>() - last_p).norm();
    last_p = x.head<3>();
    sensors.sample(t_us, x, files.raw_events());

    const Guidance::Command cmd = guidance.update(x[0], x[1]);
    if (cmd.camera_on) imaging_track.push_back({x[0], x[1]});
    // The first image 1 s into the dive, once every sensor has reported (navd initialises).
    const bool image_due = cmd.camera_on && end_us < 0 && t_us >= kDiveStartMonotonicUs + 1000000 &&
                           (last_image_us < 0 || t_us - last_image_us >= image_period_us);
    if (image_due) {
      const std::int64_t frame = sum.images++;
      const double altitude = seafloor.depth_m(x[0], x[1]) - x[2];
      sum.min_altitude_m = std::min(sum.min_altitude_m, altitude);
      sum.max_altitude_m = std::max(sum.max_altitude_m, altitude);
      altitude_sum += altitude;
      if (last_image_us >= 0) {
        const double gap_s = (t_us - last_image_us) * 1e-6;
        if (camera_was_off && sum.first_frame_after_transit < 0)
          sum.first_frame_after_transit = frame;
        sum.max_time_gap_between_images_s = std::max(sum.max_time_gap_between_images_s, gap_s);
      }
      last_image_us = t_us;
      camera_was_off = false;
      const double latency_us =
          camera_cfg.latency_s * 1e6 +
          std::uniform_real_distribution<double>(0.0, o.sensor_errors.jitter_ms * 1e3)(camera_rng);
      const std::int64_t host_us = t_us + std::llround(latency_us);
      if (o.render_images) {
        DiveFiles::Pixels px;
        char name[32];
        std::snprintf(name, sizeof name, "images/%06lld.png", static_cast<long long>(frame));
        px.file_path = name;
        const cv::Mat pixels = renderer.render(x, static_cast<std::uint64_t>(frame), &px.gain_db);
        if (!cv::imwrite((dir / name).string(), pixels))
          throw std::runtime_error((dir / name).string() + ": cannot write the PNG");
        px.thumbnail = renderer.thumbnail(pixels);
        files.image(frame, t_us, host_us, x, altitude, camera, &px);
      } else {
        files.image(frame, t_us, host_us, x, altitude, camera);
      }
      OracleImage img{frame, t_us, x, {}};
      const core::Vec6 x_wc = core::head_to_tail(x.head<6>(), camera.x_body_camera);
      img.footprint = image_footprint(camera, x, seafloor.depth_m(x_wc[0], x_wc[1]));
      for (navlcm::registration_t& r : oracle.add_image(img))
        files.registration(host_us, std::move(r));
      if (2 * sum.images >= o.mission.images) guidance.request_transit();
      if (sum.images == o.mission.images)
        end_us = t_us + 2 * 1000000;  // sensors cover the last image
    }
    if (!cmd.camera_on) camera_was_off = true;
    if (cmd.finished && end_us < 0) end_us = t_us;  // ran out of lines (should not happen)

    const double depth_cmd = seafloor.safe_depth_m(x[0], x[1]) - o.mission.altitude_m;
    const double heading_error = core::wrap_angle(cmd.heading_rad - x[5]);
    vehicle.step({cmd.heading_rad, surge_command(o, heading_error, depth_cmd - x[2]), depth_cmd},
                 dt_s);

    if (o.progress) {
      const int pct = static_cast<int>(100.0 * sum.images / o.mission.images);
      if (pct != last_progress) o.progress(pct / 100.0);
      last_progress = pct;
    }
  }
  sum.duration_s = (end_us - kDiveStartMonotonicUs) * 1e-6;
  sum.mean_altitude_m = sum.images > 0 ? altitude_sum / sum.images : 0.0;
  sum.survey_hull_area_m2 = area_m2(convex_hull(imaging_track));
  sum.sensors = sensors.counts();
  sum.registrations = oracle.counts().registrations;
  sum.registrations_succeeded = oracle.counts().succeeded;
  sum.outliers_injected = oracle.counts().outliers;
  sum.degenerate_pairs_skipped = oracle.counts().degenerate_skipped;
  sum.log_events = files.write_log();
  files.write_json(sum.to_json());
  if (o.progress) o.progress(1.0);
  return sum;
}

SimSummary simulate_dive(const SimOptions& options, const std::string& config_path) {
  const daemon::NavdConfig config = daemon::load_config_file(config_path);
  std::ifstream in(config_path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return simulate_dive(options, config, text.str());
}

}  // namespace nav::sim
