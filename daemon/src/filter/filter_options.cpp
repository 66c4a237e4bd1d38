// NavdConfig -> core::NavFilterOptions (filter/filter_options.h).
#include "nav/daemon/filter/filter_options.h"

#include <spdlog/spdlog.h>

#include "nav/core/navigation/chi_square.h"
#include "nav/daemon/filter/marginals_launcher.h"
#include "nav/daemon/filter/recovery_worker.h"

namespace nav::daemon {
namespace {

core::Vec3 to_vec3(const std::array<double, 3>& a) { return core::Vec3(a[0], a[1], a[2]); }

core::SensorModelOptions sensor_options(const SensorConfig& c) {
  core::SensorModelOptions s;
  s.name = c.name;
  s.rpy_body_sensor_rad = to_vec3(c.mount.rpy_rad);
  s.p_body_sensor_m = to_vec3(c.mount.lever_arm_m);
  s.roll_pitch_sigma_rad = c.noise.roll_pitch_rad;
  s.heading_sigma_rad = c.noise.heading_rad;
  s.velocity_sigma_mps = c.noise.velocity_mps;
  s.depth_sigma_m = c.noise.depth_m;
  if (is_camera(c.type)) {
    s.camera = core::CameraIntrinsics{c.camera.fx_px, c.camera.fy_px, c.camera.cx_px,
                                      c.camera.cy_px};
  }
  return s;
}

}  // namespace

core::NavFilterOptions filter_options_from_config(const NavdConfig& config) {
  core::NavFilterOptions o;
  o.sensors.reserve(config.sensors.size());
  for (const SensorConfig& c : config.sensors) o.sensors.push_back(sensor_options(c));
  o.process_noise = config.filter.process_noise;
  o.recovery.mode = core::RecoveryMode::kFixedIterations;
  o.recovery.iterations_per_step = config.filter.cg_iterations_per_step;
  o.recovery.preconditioner = config.filter.recovery_preconditioner;
  o.recovery.keep_factor_equal = config.filter.recovery_keep_factor_equal;
  o.recovery.refresh_interval = config.filter.recovery_refresh_interval;
  o.recovery.refresh_residual = config.filter.recovery_refresh_residual;
  o.recovery.kept_factor_recent_blocks = config.filter.recovery_kept_recent_states;
  o.recovery.renewal_lag = config.filter.recovery_renewal_lag;
  o.recovery.refresh_growth = config.filter.recovery_refresh_growth;
  if (o.recovery.renewal_lag > 0) o.renewal_launcher = threaded_marginals_launcher();
  o.camera_gate_chi2 =
      core::equivalent_chi_square_gate(config.filter.gating_chi2_threshold, 6, 5);
  o.aid_gate = config.filter.aid_gate;
  o.recovery_thread = config.filter.recovery_thread;
  o.recovery_handoff_s = config.filter.recovery_handoff_s;
  if (o.recovery_thread) o.recovery_executor = threaded_recovery_executor();
  o.registration_wait_s = config.filter.registration_wait_s;
  o.max_pending_registrations = config.filter.max_pending_registrations;
  o.proposal.min_probability = config.filter.proposal_min_probability;
  o.proposal.min_overlap_fraction = config.filter.proposal_min_overlap;
  o.proposal.max_per_image = config.filter.proposal_max_per_image;
  o.warn = [](const std::string& message) { spdlog::warn("{}", message); };
  return o;
}

}  // namespace nav::daemon
