// navd config: ConfigError, the top-level document and the filter / lcm / checkpoint /
// realtime / sim / vision sections.
// Schema in config.h and config/README.md.
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <sstream>
#include <string_view>

#include "config_sections.h"

namespace nav::daemon {
namespace {

using detail::YamlReader;

std::string error_text(const std::string& source, const std::string& key_path,
                       const std::string& reason) {
  return source + ": " + (key_path.empty() ? "<root>" : key_path) + ": " + reason;
}

/// N numbers, each in [lo, hi]; `names` (e.g. " [roll, pitch]") follows the count in the error.
template <int N>
Eigen::Matrix<double, N, 1> read_numbers(const YamlReader& r, double lo, double hi,
                                         const std::string& names = "") {
  const std::vector<YamlReader> items = r.elements();
  if (items.size() != N) {
    r.fail("expected " + std::to_string(N) + " numbers" + names + ", got " +
           std::to_string(items.size()));
  }
  Eigen::Matrix<double, N, 1> out;
  for (int i = 0; i < N; ++i) {
    const YamlReader& item = items[static_cast<std::size_t>(i)];
    const double v = item.as_double();
    if (v < lo || v > hi) item.fail(std::to_string(v) + " is not in " + detail::range_text(lo, hi));
    out[i] = v;
  }
  return out;
}

/// Roll and pitch values, each in [lo, hi].
Eigen::Vector2d read_pair(const YamlReader& r, double lo, double hi) {
  return read_numbers<2>(r, lo, hi, " [roll, pitch]");
}

/// filter.attitude_restoring (core AttitudeRestoringOptions; angles in degrees here).
core::AttitudeRestoringOptions parse_attitude_restoring(const YamlReader& a) {
  a.expect_map({"natural_period_s", "damping_ratio", "trim_deg", "pitch_per_heave_deg_per_mps"});
  constexpr double kRadPerDeg = std::numbers::pi / 180.0;
  core::AttitudeRestoringOptions o;
  if (a.has("natural_period_s"))
    o.natural_period_s = read_pair(a.at("natural_period_s"), 0.0, 3600.0);
  if (a.has("damping_ratio")) o.damping_ratio = read_pair(a.at("damping_ratio"), 0.0, 100.0);
  if (a.has("trim_deg")) o.trim_rad = kRadPerDeg * read_pair(a.at("trim_deg"), -45.0, 45.0);
  double per_heave_deg = 0.0;
  a.read("pitch_per_heave_deg_per_mps", per_heave_deg, -90.0, 90.0);
  o.pitch_per_heave_rad_per_mps = kRadPerDeg * per_heave_deg;
  return o;
}

FilterConfig parse_filter(const YamlReader& f) {
  f.expect_map({"process_noise_psd",
                "attitude_restoring",
                "cg_iterations_per_step",
                "latency_window_ms",
                "gating_chi2_threshold",
                "recovery_thread",
                "recovery_handoff_s",
                "recovery_preconditioner",
                "recovery_refresh_interval",
                "recovery_refresh_residual",
                "recovery_kept_recent_states",
                "recovery_renewal_lag",
                "recovery_refresh_growth",
                "registration_wait_s",
                "max_pending_registrations",
                "proposal_min_probability",
                "proposal_min_overlap",
                "proposal_max_per_image",
                "dvl_gate_sigma",
                "roll_pitch_gate_sigma",
                "heading_gate_sigma",
                "depth_gate_sigma",
                "aid_gate_reset_s"});
  FilterConfig filter;
  if (f.has("process_noise_psd")) {
    const YamlReader p = f.at("process_noise_psd");
    p.expect_map({"accel_m2ps3", "angular_accel_rad2ps3"});
    if (p.has("accel_m2ps3")) {
      filter.process_noise.accel_psd = read_numbers<3>(p.at("accel_m2ps3"), 0.0, 1e3);
    }
    if (p.has("angular_accel_rad2ps3")) {
      filter.process_noise.angular_accel_psd =
          read_numbers<3>(p.at("angular_accel_rad2ps3"), 0.0, 1e3);
    }
  }
  if (f.has("attitude_restoring")) {
    filter.process_noise.attitude_restoring = parse_attitude_restoring(f.at("attitude_restoring"));
  }
  f.read("cg_iterations_per_step", filter.cg_iterations_per_step, 1, 1000);
  f.read("latency_window_ms", filter.latency_window_ms, 0.0, 60000.0);
  f.read("gating_chi2_threshold", filter.gating_chi2_threshold, 1e-6, 1e6);
  if (f.has("recovery_thread")) filter.recovery_thread = f.at("recovery_thread").as_bool();
  f.read("recovery_handoff_s", filter.recovery_handoff_s, 0.0, 3600.0);
  if (f.has("recovery_preconditioner")) {
    const std::string name = f.at("recovery_preconditioner").as_string();
    if (name == "factor" || name == "kept_factor") {
      filter.recovery_preconditioner = core::RecoveryPreconditioner::kFactor;
      filter.recovery_keep_factor_equal = name == "kept_factor";
    } else if (name != "block_jacobi") {
      f.at("recovery_preconditioner")
          .fail("'" + name + "' must be block_jacobi, factor or kept_factor");
    }
  }
  f.read("recovery_refresh_interval", filter.recovery_refresh_interval, 1, 100000);
  f.read("recovery_refresh_residual", filter.recovery_refresh_residual, 1e-12, 1e12);
  f.read("recovery_kept_recent_states", filter.recovery_kept_recent_states, 0, 100000);
  f.read("recovery_renewal_lag", filter.recovery_renewal_lag, 0, 99999);
  f.read("recovery_refresh_growth", filter.recovery_refresh_growth, 0.0, 1e6);
  if (filter.recovery_renewal_lag > 0 &&
      !(filter.recovery_keep_factor_equal &&
        filter.recovery_renewal_lag < filter.recovery_refresh_interval)) {
    f.at("recovery_renewal_lag")
        .fail(
            "must be 0 unless recovery_preconditioner is kept_factor, and below "
            "recovery_refresh_interval (" +
            std::to_string(filter.recovery_refresh_interval) + ")");
  }
  f.read("registration_wait_s", filter.registration_wait_s, 0.0, 3600.0);
  f.read("max_pending_registrations", filter.max_pending_registrations, 1, 100000);
  f.read("proposal_min_probability", filter.proposal_min_probability, 1e-9, 1.0 - 1e-9);
  f.read("proposal_min_overlap", filter.proposal_min_overlap, 1e-3, 1.0);
  f.read("proposal_max_per_image", filter.proposal_max_per_image, 1, 100000);
  f.read("dvl_gate_sigma", filter.aid_gate.dvl_sigma, 0.0, 1000.0);
  f.read("roll_pitch_gate_sigma", filter.aid_gate.roll_pitch_sigma, 0.0, 1000.0);
  f.read("heading_gate_sigma", filter.aid_gate.heading_sigma, 0.0, 1000.0);
  f.read("depth_gate_sigma", filter.aid_gate.depth_sigma, 0.0, 1000.0);
  f.read("aid_gate_reset_s", filter.aid_gate.reset_timeout_s, 0.0, 1e6);
  return filter;
}

void parse_channel(const YamlReader& parent, std::string_view key, LcmChannel& out) {
  if (!parent.has(key)) return;
  const YamlReader c = parent.at(key);
  c.expect_map({"name", "rate_hz"});
  c.read("name", out.name);
  c.read("rate_hz", out.rate_hz, 1e-3, 1000.0);
}

LcmConfig parse_lcm(const YamlReader& l) {
  l.expect_map({"url", "channels", "registration_signing"});
  LcmConfig lcm;
  l.read("url", lcm.url);
  const std::string_view schemes[] = {"udpm://", "file://", "memq://"};
  bool known = false;
  for (std::string_view s : schemes) known = known || lcm.url.rfind(s, 0) == 0;
  if (!known) l.at("url").fail("'" + lcm.url + "' must start with udpm://, file:// or memq://");
  if (l.has("channels")) {
    const YamlReader c = l.at("channels");
    c.expect_map({"nav_solution", "health", "bounds", "bounds_snapshot", "camera_links",
                  "registration", "link_proposals"});
    parse_channel(c, "nav_solution", lcm.nav_solution);
    parse_channel(c, "health", lcm.health);
    parse_channel(c, "bounds", lcm.bounds);
    parse_channel(c, "bounds_snapshot", lcm.bounds_snapshot);
    parse_channel(c, "camera_links", lcm.camera_links);
    parse_channel(c, "registration", lcm.registration);
    parse_channel(c, "link_proposals", lcm.link_proposals);
  }
  if (l.has("registration_signing")) {
    const YamlReader g = l.at("registration_signing");
    g.expect_map({"key_file", "window_s"});
    g.read("key_file", lcm.registration_signing.key_file, true);
    if (lcm.registration_signing.key_file.empty()) g.at("key_file").fail("must not be empty");
    g.read("window_s", lcm.registration_signing.window_s, 1e-3, 3600.0);
  }
  return lcm;
}

CheckpointConfig parse_checkpoint(const YamlReader& c) {
  c.expect_map({"path", "period_s", "keep"});
  CheckpointConfig checkpoint;
  c.read("path", checkpoint.path);
  c.read("period_s", checkpoint.period_s, 1e-3, 86400.0);
  c.read("keep", checkpoint.keep, 1, 100);
  return checkpoint;
}

RealtimeConfig parse_realtime(const YamlReader& r) {
  r.expect_map({"device_priority", "filter_priority", "lock_memory"});
  RealtimeConfig realtime;
  r.read("device_priority", realtime.device_priority, 0, 99);
  r.read("filter_priority", realtime.filter_priority, 0, 99);
  if (r.has("lock_memory")) realtime.lock_memory = r.at("lock_memory").as_bool();
  return realtime;
}

SimDiveConfig parse_sim(const YamlReader& c) {
  c.expect_map({"dive_dir", "seed", "images", "outlier_rate"});
  SimDiveConfig sim;
  c.read("dive_dir", sim.dive_dir, true);
  c.read("seed", sim.seed, 0, 2147483647);
  c.read("images", sim.images, 2, 100000);
  c.read("outlier_rate", sim.outlier_rate, 0.0, 1.0);
  return sim;
}

VisionConfig parse_vision(const YamlReader& v) {
  v.expect_map({"enabled", "threads", "cache_images", "queue_capacity", "answer_delay_s",
                "image_dir", "image_width_px", "image_height_px", "depth_sigma_fraction",
                "depth_sigma_floor_m", "max_leverage", "pixel_sigma_px", "residual_sigma_factor",
                "model_sigma_deg", "systematic_noise_fraction", "min_inliers", "max_sigma_deg",
                "uncertain_min_inliers", "band_floor_sigma_px"});
  VisionConfig vision;
  if (v.has("enabled")) vision.enabled = v.at("enabled").as_bool();
  v.read("threads", vision.threads, 1, 64);
  v.read("cache_images", vision.cache_images, 2, 100000);
  v.read("queue_capacity", vision.queue_capacity, 1, 100000);
  v.read("answer_delay_s", vision.answer_delay_s, 0.0, 3600.0);
  v.read("image_dir", vision.image_dir);
  v.read("image_width_px", vision.image_width_px, 0, 100000);
  v.read("image_height_px", vision.image_height_px, 0, 100000);
  v.read("depth_sigma_fraction", vision.depth_sigma_fraction, 0.0, 10.0);
  v.read("depth_sigma_floor_m", vision.depth_sigma_floor_m, 0.0, 1000.0);
  v.read("pixel_sigma_px", vision.pixel_sigma_px, 1e-3, 10.0);
  v.read("residual_sigma_factor", vision.residual_sigma_factor, 0.1, 10.0);
  v.read("model_sigma_deg", vision.model_sigma_deg, 0.0, 10.0);
  v.read("systematic_noise_fraction", vision.systematic_noise_fraction, 0.0, 10.0);
  // Keys whose absence leaves the registration pipeline's default.
  const auto read_optional = [&v]<typename T>(std::string_view key, T lo, T hi) {
    T value = lo;
    v.read(key, value, lo, hi);
    return v.has(key) ? std::optional<T>(value) : std::nullopt;
  };
  vision.max_leverage = read_optional("max_leverage", 1e-6, 1.0);
  vision.min_inliers = read_optional("min_inliers", 5, 100000);
  vision.max_sigma_deg = read_optional("max_sigma_deg", 1e-3, 180.0);
  vision.band_floor_sigma_px = read_optional("band_floor_sigma_px", 0.0, 1000.0);
  vision.uncertain_min_inliers = read_optional("uncertain_min_inliers", 5, 100000);
  return vision;
}

}  // namespace

ConfigError::ConfigError(const std::string& source, std::string key_path, std::string reason)
    : std::runtime_error(error_text(source, key_path, reason)),
      key_path_(std::move(key_path)),
      reason_(std::move(reason)) {}

const char* to_string(SensorType type) {
  switch (type) {
    case SensorType::kDvlPd0:
      return "dvl_pd0";
    case SensorType::kDvlPd6:
      return "dvl_pd6";
    case SensorType::kDvlCan:
      return "dvl_can";
    case SensorType::kHeadingNmea:
      return "heading_nmea";
    case SensorType::kFogKvh:
      return "fog_kvh";
    case SensorType::kPressureParo:
      return "pressure_paro";
    case SensorType::kAltimeter:
      return "altimeter";
    case SensorType::kCameraGige:
      return "camera_gige";
    case SensorType::kCameraV4l2:
      return "camera_v4l2";
  }
  return "unknown";
}

bool is_camera(SensorType type) {
  return type == SensorType::kCameraGige || type == SensorType::kCameraV4l2;
}

NavdConfig parse_config(const std::string& yaml_text, const std::string& source,
                        const std::string& base_dir) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source, "",
                      "YAML syntax error at line " + std::to_string(e.mark.line + 1) + ", column " +
                          std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  const YamlReader doc(root, "", &source);
  doc.expect_map({"sensors", "filter", "lcm", "checkpoint", "realtime", "sim", "vision"});
  NavdConfig config;
  config.sensors = detail::parse_sensors(doc.at("sensors"), base_dir);
  if (doc.has("filter")) config.filter = parse_filter(doc.at("filter"));
  if (doc.has("lcm")) config.lcm = parse_lcm(doc.at("lcm"));
  if (doc.has("checkpoint")) config.checkpoint = parse_checkpoint(doc.at("checkpoint"));
  if (doc.has("realtime")) config.realtime = parse_realtime(doc.at("realtime"));
  if (doc.has("sim")) config.sim = parse_sim(doc.at("sim"));
  if (doc.has("vision")) config.vision = parse_vision(doc.at("vision"));
  return config;
}

NavdConfig load_config_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path, "", "cannot open file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(path, "", "read error");
  return parse_config(text.str(), path, std::filesystem::path(path).parent_path().string());
}

}  // namespace nav::daemon
