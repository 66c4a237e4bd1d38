// Field-by-field JSON of navd's LCM types (lcmtypes/*.lcm) with derived display values.
#include "nav/daemon/topside/lcm_json.h"

#include <cmath>

#include "nav/daemon/topside/ellipse.h"

namespace nav::daemon::topside {
namespace {

template <typename T, std::size_t N>
nlohmann::json array_json(const T (&values)[N]) {
  nlohmann::json a = nlohmann::json::array();
  for (const T& v : values) a.push_back(v);
  return a;
}

nlohmann::json ellipse_json(const Ellipse2& e) {
  return {{"semi_major_m", e.semi_major_m},
          {"semi_minor_m", e.semi_minor_m},
          {"angle_rad", e.angle_rad}};
}

}  // namespace

nlohmann::json to_json(const navlcm::nav_solution_t& m) {
  const double* P = m.pose_covariance;
  const Ellipse2 one_sigma = covariance_ellipse(P[0], P[1], P[7], 1.0);
  return {{"utime", m.utime},
          {"time_of_validity_us", m.time_of_validity_us},
          {"p_world_m", array_json(m.p_world_m)},
          {"rph_rad", array_json(m.rph_rad)},
          {"v_body_mps", array_json(m.v_body_mps)},
          {"omega_body_radps", array_json(m.omega_body_radps)},
          {"pose_covariance", array_json(m.pose_covariance)},
          {"num_delayed_states", m.num_delayed_states},
          {"num_camera_links", m.num_camera_links},
          {"filter_status", static_cast<int>(m.filter_status)},
          {"depth_m", m.p_world_m[2]},
          {"heading_rad", m.rph_rad[2]},
          {"speed_mps", std::hypot(m.v_body_mps[0], m.v_body_mps[1], m.v_body_mps[2])},
          {"sigma_xy_m", one_sigma.semi_major_m},
          {"sigma_z_m", std::sqrt(std::max(P[14], 0.0))},
          {"ellipse_1sigma", ellipse_json(one_sigma)}};
}

nlohmann::json to_json(const navlcm::aid_source_t& m) {
  return {{"time_of_validity_us", m.time_of_validity_us},
          {"observation", m.observation},
          {"observation_variance", m.observation_variance},
          {"innovation", m.innovation},
          {"innovation_variance", m.innovation_variance},
          {"test_ratio", m.test_ratio},
          {"rejected", m.rejected != 0},
          {"fused", m.fused != 0}};
}

nlohmann::json to_json(const navlcm::sensor_health_t& m) {
  nlohmann::json last = nlohmann::json::array();
  for (const auto& a : m.last) last.push_back(to_json(a));
  return {{"name", m.name},
          {"rate_hz", m.rate_hz},
          {"records", m.records},
          {"decode_errors", m.decode_errors},
          {"dropped_bytes", m.dropped_bytes},
          {"queue_drops", m.queue_drops},
          {"late_measurements", m.late_measurements},
          {"bytes", m.bytes},
          {"measurements", m.measurements},
          {"reconnects", m.reconnects},
          {"last_message_age_s", m.last_message_age_s},
          {"connected", m.connected != 0},
          {"updates", m.updates},
          {"rejected_updates", m.rejected_updates},
          {"nis_mean", m.nis_mean},
          {"nis_expected", m.nis_expected},
          {"nis_last", m.nis_last},
          {"last", std::move(last)}};
}

nlohmann::json to_json(const navlcm::health_t& m) {
  nlohmann::json sensors = nlohmann::json::array();
  for (const auto& s : m.sensors) sensors.push_back(to_json(s));
  return {{"utime", m.utime},
          {"sensors", std::move(sensors)},
          {"queue_depth", m.queue_depth},
          {"queue_capacity", m.queue_capacity},
          {"cg_relative_residual", m.cg_relative_residual},
          {"cg_iterations", m.cg_iterations},
          {"cpu_percent", m.cpu_percent},
          {"rss_mb", m.rss_mb},
          {"peak_rss_mb", m.peak_rss_mb},
          {"status", m.status},
          {"registrations_received", m.registrations_received},
          {"registrations_rejected",
           {{"wrong_run", m.registrations_wrong_run},
            {"unknown_sequence", m.registrations_unknown_sequence},
            {"expired", m.registrations_expired},
            {"already_answered", m.registrations_already_answered},
            {"pair_mismatch", m.registrations_pair_mismatch},
            {"invalid", m.registrations_invalid},
            {"unsigned", m.registrations_unsigned},
            {"bad_signature", m.registrations_bad_signature},
            {"stale_signature", m.registrations_stale_signature}}}};
}

nlohmann::json to_json(const navlcm::delayed_state_bound_t& m) {
  const double* S = m.bound_covariance;
  return {{"utime", m.utime},
          {"state_id", m.state_id},
          {"image_time_us", m.image_time_us},
          {"mean_pose", array_json(m.mean_pose)},
          {"bound_covariance", array_json(m.bound_covariance)},
          {"num_tightenings", m.num_tightenings},
          {"ellipse_3sigma", ellipse_json(covariance_ellipse(S[0], S[1], S[7], 3.0))}};
}

nlohmann::json to_json(const navlcm::bounds_snapshot_t& m) {
  nlohmann::json states = nlohmann::json::array();
  for (const auto& s : m.states) states.push_back(to_json(s));
  return {{"utime", m.utime}, {"states", std::move(states)}};
}

nlohmann::json to_json(const navlcm::camera_link_t& m) {
  return {{"utime", m.utime},
          {"state_id_i", m.state_id_i},
          {"state_id_j", m.state_id_j},
          {"measurement", array_json(m.measurement)},
          {"innovation", array_json(m.innovation)},
          {"mahalanobis_sq", m.mahalanobis_sq},
          {"accepted", m.accepted != 0},
          {"reason", m.reason}};
}

nlohmann::json to_json(const navlcm::link_proposal_t& m) {
  return {{"utime", m.utime},
          {"sequence", m.sequence},
          {"frame_id_i", m.frame_id_i},
          {"frame_id_j", m.frame_id_j},
          {"time_of_validity_i_us", m.time_of_validity_i_us},
          {"time_of_validity_j_us", m.time_of_validity_j_us},
          {"deadline_utime", m.deadline_utime},
          {"image_file_i", m.image_file_i},
          {"image_file_j", m.image_file_j},
          {"run_id", m.run_id}};
}

nlohmann::json to_json(const navlcm::image_metadata_t& m) {
  return {{"utime", m.utime},
          {"time_of_validity_us", m.time_of_validity_us},
          {"frame_id", m.frame_id},
          {"state_id", m.state_id},
          {"file_path", m.file_path},
          {"width", m.width},
          {"height", m.height},
          {"bits_per_pixel", m.bits_per_pixel},
          {"exposure_us", m.exposure_us},
          {"gain_db", m.gain_db},
          {"thumbnail_num_bytes", m.thumbnail_num_bytes}};
}

}  // namespace nav::daemon::topside
