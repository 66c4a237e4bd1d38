// ReplaySummary and LinkOutcomeCounts: see replay_summary.h.
#include "nav/daemon/replay/replay_summary.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "nav/core/recovery/consistency.h"
#include "nav/daemon/replay/dive_replay.h"
#include "nav/daemon/replay/output_schema.h"
#include "nav/daemon/replay/proposal_recall.h"

namespace nav::daemon {
namespace {

using nlohmann::json;
using output_schema::LinksCsv;

json pose_json(const core::Vec6& x) {
  return {{"x_m", x(0)},      {"y_m", x(1)},       {"z_m", x(2)},
          {"roll_rad", x(3)}, {"pitch_rad", x(4)}, {"heading_rad", x(5)}};
}

json optional_pose_json(const std::optional<core::Vec6>& x) {
  return x ? pose_json(*x) : json(nullptr);
}

/// The robot's published pose (robot_mean(): after every update), or none while the filter has
/// no state yet (e.g. dead reckoning in a resumed replay stopped before its first measurements).
/// Filter: core::NavFilter or core::DeadReckoningFilter.
template <class Filter>
std::optional<core::Vec6> robot_pose(const Filter& filter) {
  if (!filter.initialised()) return std::nullopt;
  return core::Vec12(filter.robot_mean()).head<6>();
}

/// Per sensor name: the updates the filter did not fuse (innovation_stats.h `rejected`).
template <class Filter>
std::map<std::string, std::uint64_t> rejected_by_sensor(const Filter& filter) {
  std::map<std::string, std::uint64_t> rejected;
  for (const core::SensorInnovation& r : filter.innovations().sensors()) {
    rejected[r.name] = r.rejected;
  }
  return rejected;
}

// Readers for from_json: a key that is absent or of another type leaves `out` unchanged.
void read(const json& j, const char* key, double& out) {
  if (auto it = j.find(key); it != j.end() && it->is_number()) out = it->get<double>();
}
void read(const json& j, const char* key, std::uint64_t& out) {
  if (auto it = j.find(key); it != j.end() && it->is_number_unsigned()) {
    out = it->get<std::uint64_t>();
  }
}
void read(const json& j, const char* key, std::int64_t& out) {
  if (auto it = j.find(key); it != j.end() && it->is_number_integer()) {
    out = it->get<std::int64_t>();
  }
}
void read(const json& j, const char* key, std::string& out) {
  if (auto it = j.find(key); it != j.end() && it->is_string()) out = it->get<std::string>();
}
void read(const json& j, const char* key, std::optional<std::string>& out) {
  if (auto it = j.find(key); it != j.end() && it->is_string()) out = it->get<std::string>();
}
void read(const json& j, const char* key, std::optional<core::Vec6>& out) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_object()) return;
  core::Vec6 x = core::Vec6::Constant(ReplaySummary::kUnset);
  const char* kKeys[6] = {"x_m", "y_m", "z_m", "roll_rad", "pitch_rad", "heading_rad"};
  for (int k = 0; k < 6; ++k) read(*it, kKeys[k], x(k));
  out = x;
}
/// An object of counts; entries that are not unsigned integers are skipped.
void read(const json& j, const char* key, std::map<std::string, std::uint64_t>& out) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_object()) return;
  for (const auto& [name, n] : it->items()) {
    if (n.is_number_unsigned()) out[name] = n.get<std::uint64_t>();
  }
}

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

}  // namespace

void LinkOutcomeCounts::add(std::string_view outcome, bool is_outlier) {
  std::uint64_t* counter = nullptr;
  if (outcome == LinksCsv::kOutcomes[0]) counter = &accepted;
  if (outcome == LinksCsv::kOutcomes[1]) counter = &gated;
  if (outcome == LinksCsv::kOutcomes[2]) counter = &registration_failed;
  if (outcome == LinksCsv::kOutcomes[3]) counter = &not_registered;
  if (!counter) {
    throw std::invalid_argument("link outcome '" + std::string(outcome) +
                                "' is not one of accepted, gated, registration_failed, "
                                "not_registered");
  }
  ++proposed;
  ++*counter;
  if (is_outlier) {
    ++outliers_proposed;
    ++(counter == &accepted ? outliers_accepted : outliers_rejected);
  }
}

std::string ReplaySummary::to_json() const {
  json j;
  if (dive_dir) j["dive_dir"] = *dive_dir;
  j["log"] = log;
  j["config"] = config;
  j["images"] = images;
  j["delayed_states"] = delayed_states;
  j["camera_links"] = camera_links;
  j["wall_s"] = wall_s;
  j["log_span_s"] = log_span_s;
  j["realtime_factor"] = realtime_factor;
  j["analysis_s"] = analysis_s;
  j["final_pose"] = pose_json(final_pose);
  j["final_pose_running"] = optional_pose_json(final_pose_running);
  if (has_dead_reckoning) {
    j["dead_reckoning_final_pose"] = optional_pose_json(dead_reckoning_final_pose);
    j["dead_reckoning_rejected_updates"] = dead_reckoning_rejected_updates;
  }
  j["max_cg_relative_residual"] = max_cg_relative_residual;
  j["cg_iterations_per_image"] = cg_iterations_per_image;
  j["recovery"] = recovery;
  j["candidates"] = candidates;
  j["links_proposed"] = links.proposed;
  j["links_accepted"] = links.accepted;
  j["links_gated"] = links.gated;
  j["registration_failed"] = links.registration_failed;
  j["not_registered"] = links.not_registered;
  j["outliers_rejected"] = links.outliers_rejected;
  j["outliers_accepted"] = links.outliers_accepted;
  j["camera_gate_chi2_5dof"] = camera_gate_chi2_5dof;
  j["registrations"] = registrations;
  j["registration_outliers"] = registration_outliers;
  j["proposals_per_image_mean"] = proposals_per_image_mean;
  j["proposal_recall"] = proposal_recall;
  j["published_nees_mean"] = published_nees_mean;
  j["published_nees_exceed_99_fraction"] = published_nees_exceed_99_fraction;
  j["time_of_use_checks"] = time_of_use_checks;
  j["time_of_use_s"] = time_of_use_s;
  j["time_of_use_conservative_fraction"] = time_of_use_conservative_fraction;
  j["time_of_use_joint_conservative_fraction"] = time_of_use_joint_conservative_fraction;
  j["time_of_use_worst_min_eigenvalue"] = time_of_use_worst_min_eigenvalue;
  j["logdet_ratio_relative_ours_median"] = logdet_ratio_relative_ours_median;
  j["logdet_ratio_relative_markov_blanket_median"] = logdet_ratio_relative_markov_blanket_median;
  j["conservative_fraction"] = conservative_fraction;
  j["states_checked"] = states_checked;
  j["measurements"] = measurements;
  j["updates"] = updates;
  j["update_failures"] = update_failures;
  j["rejected_updates"] = rejected_updates;
  j["recovery_failures"] = recovery_failures;
  j["bound_update_failures"] = bound_update_failures;
  j["before_initialisation"] = before_initialisation;
  j["decode_errors"] = decode_errors;
  j["late_dropped"] = late_dropped;
  j["ordering_full_dropped"] = ordering_full_dropped;
  j["error"] = error;
  return j.dump();
}

std::string ReplaySummary::brief_report() const {
  std::string s = "replay: " + std::to_string(images) + " images, " +
                  std::to_string(delayed_states) + " delayed states, " +
                  std::to_string(links.accepted) + " of " + std::to_string(links.proposed) +
                  " proposed links accepted, " + std::to_string(links.outliers_rejected) + " of " +
                  std::to_string(links.outliers_rejected + links.outliers_accepted) +
                  " outliers rejected, conservative " + format("%.3g", conservative_fraction) +
                  ", " + format("%.3g", wall_s) + " s wall (" + format("%.0f", realtime_factor) +
                  "x real time), ";
  return s + (error.empty() ? "ok" : "error: " + error);
}

ReplaySummary ReplaySummary::from_json(const std::string& text, const std::string& source) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw std::invalid_argument(source + ": not valid JSON: " + e.what());
  }
  if (!j.is_object()) throw std::invalid_argument(source + ": not a JSON object");
  ReplaySummary s;
  read(j, "dive_dir", s.dive_dir);
  read(j, "log", s.log);
  read(j, "config", s.config);
  read(j, "images", s.images);
  read(j, "delayed_states", s.delayed_states);
  read(j, "camera_links", s.camera_links);
  read(j, "wall_s", s.wall_s);
  read(j, "log_span_s", s.log_span_s);
  read(j, "realtime_factor", s.realtime_factor);
  read(j, "analysis_s", s.analysis_s);
  std::optional<core::Vec6> final_pose;
  read(j, "final_pose", final_pose);
  if (final_pose) s.final_pose = *final_pose;
  read(j, "final_pose_running", s.final_pose_running);
  s.has_dead_reckoning = j.contains("dead_reckoning_final_pose");
  read(j, "dead_reckoning_final_pose", s.dead_reckoning_final_pose);
  read(j, "max_cg_relative_residual", s.max_cg_relative_residual);
  read(j, "cg_iterations_per_image", s.cg_iterations_per_image);
  read(j, "recovery", s.recovery);
  read(j, "candidates", s.candidates);
  read(j, "links_proposed", s.links.proposed);
  read(j, "links_accepted", s.links.accepted);
  read(j, "links_gated", s.links.gated);
  read(j, "registration_failed", s.links.registration_failed);
  read(j, "not_registered", s.links.not_registered);
  read(j, "outliers_rejected", s.links.outliers_rejected);
  read(j, "outliers_accepted", s.links.outliers_accepted);
  read(j, "camera_gate_chi2_5dof", s.camera_gate_chi2_5dof);
  read(j, "registrations", s.registrations);
  read(j, "registration_outliers", s.registration_outliers);
  read(j, "proposals_per_image_mean", s.proposals_per_image_mean);
  read(j, "proposal_recall", s.proposal_recall);
  read(j, "published_nees_mean", s.published_nees_mean);
  read(j, "published_nees_exceed_99_fraction", s.published_nees_exceed_99_fraction);
  read(j, "time_of_use_checks", s.time_of_use_checks);
  read(j, "time_of_use_s", s.time_of_use_s);
  read(j, "time_of_use_conservative_fraction", s.time_of_use_conservative_fraction);
  read(j, "time_of_use_joint_conservative_fraction", s.time_of_use_joint_conservative_fraction);
  read(j, "time_of_use_worst_min_eigenvalue", s.time_of_use_worst_min_eigenvalue);
  read(j, "logdet_ratio_relative_ours_median", s.logdet_ratio_relative_ours_median);
  read(j, "logdet_ratio_relative_markov_blanket_median",
       s.logdet_ratio_relative_markov_blanket_median);
  read(j, "conservative_fraction", s.conservative_fraction);
  read(j, "states_checked", s.states_checked);
  read(j, "measurements", s.measurements);
  read(j, "updates", s.updates);
  read(j, "update_failures", s.update_failures);
  read(j, "rejected_updates", s.rejected_updates);
  read(j, "dead_reckoning_rejected_updates", s.dead_reckoning_rejected_updates);
  read(j, "recovery_failures", s.recovery_failures);
  read(j, "bound_update_failures", s.bound_update_failures);
  read(j, "before_initialisation", s.before_initialisation);
  read(j, "decode_errors", s.decode_errors);
  read(j, "late_dropped", s.late_dropped);
  read(j, "ordering_full_dropped", s.ordering_full_dropped);
  read(j, "error", s.error);
  return s;
}

namespace {

double median_or_unset(const std::vector<double>& v) {
  return v.empty() ? ReplaySummary::kUnset : core::summarize(v).median;
}

void add_time_of_use(const ReplayRun& run, ReplaySummary& s) {
  const core::TimeOfUseStats& t = run.time_of_use;
  s.time_of_use_checks = static_cast<std::uint64_t>(t.checks);
  if (t.checks == 0) return;
  s.time_of_use_s = run.time_of_use_s;
  s.time_of_use_conservative_fraction = t.bounds_conservative_fraction();
  s.time_of_use_joint_conservative_fraction = t.joints_conservative_fraction();
  s.time_of_use_worst_min_eigenvalue = t.worst_min_eigenvalue;
  s.logdet_ratio_relative_ours_median = median_or_unset(t.ours());
  s.logdet_ratio_relative_markov_blanket_median = median_or_unset(t.markov_blanket());
}

}  // namespace

ReplaySummary make_replay_summary(const ReplayRun& run, const ReplayAnalysis& analysis,
                                  const std::string& dive_dir, const std::string& config_path) {
  const NavFilterCounters& c = run.slam->counters();
  ReplaySummary s;
  s.dive_dir = dive_dir;
  s.log = run.log_path;
  s.config = config_path;
  s.images = c.images;
  s.delayed_states = run.slam->esdf().num_blocks() - 1;
  s.camera_links = c.links_accepted;
  s.wall_s = run.wall_s;
  s.log_span_s = run.log_span_s;
  s.realtime_factor = run.wall_s > 0.0 ? run.log_span_s / run.wall_s : 0.0;
  s.analysis_s = analysis.analysis_s;
  s.final_pose = analysis.robot_mean.head<6>();
  s.final_pose_running = robot_pose(*run.slam);
  s.has_dead_reckoning = run.dead_reckoning != nullptr;
  if (run.dead_reckoning) {
    s.dead_reckoning_final_pose = robot_pose(*run.dead_reckoning);
    s.dead_reckoning_rejected_updates = rejected_by_sensor(*run.dead_reckoning);
  }
  s.max_cg_relative_residual = c.max_cg_relative_residual;
  s.cg_iterations_per_image = run.slam->options().recovery.iterations_per_step;
  s.recovery = run.slam->options().recovery_thread
                   ? "recovery thread, taken at data time image + recovery_handoff_s "
                     "(deterministic)"
                   : "synchronous at each image (deterministic)";
  s.candidates = c.candidates;
  s.links.proposed = c.links_proposed;
  s.links.accepted = c.links_accepted;
  s.links.gated = c.links_gated;
  s.links.registration_failed = c.registration_failed;
  s.links.not_registered = c.not_registered;
  s.links.outliers_rejected = c.outliers_rejected;
  s.links.outliers_accepted = c.outliers_accepted;
  s.links.outliers_proposed = c.outliers_rejected + c.outliers_accepted;
  s.camera_gate_chi2_5dof = run.slam->options().camera_gate_chi2;
  s.registrations = run.registrations->size();
  s.registration_outliers = run.registrations->outliers();
  const ProposalRecall recall = proposal_recall(*run.slam, *run.registrations);
  if (!run.slam->proposals().empty()) s.proposals_per_image_mean = recall.proposals_per_image_mean;
  s.proposal_recall = recall.recall().value_or(ReplaySummary::kUnset);
  add_time_of_use(run, s);
  s.conservative_fraction = analysis.conservative_fraction;
  s.states_checked = analysis.states.size();
  s.measurements = c.measurements;
  s.updates = c.updates;
  s.update_failures = c.update_failures;
  s.rejected_updates = rejected_by_sensor(*run.slam);
  s.recovery_failures = c.recovery_failures;
  s.bound_update_failures = c.bound_update_failures;
  s.before_initialisation = c.before_initialisation;
  s.decode_errors = run.source.decode_errors;
  s.late_dropped = run.ordering.dropped_late;
  s.ordering_full_dropped = run.ordering.dropped_full;
  s.error = run.error.empty() ? analysis.error : run.error;
  return s;
}

std::string replay_summary_json(const ReplaySummary& summary, const ReplayRun& run) {
  const std::string json = summary.to_json();
  if (!run.vision) return json;
  // vision.enabled: navd's own vision stage (vision/vision_link.h), its counters at the end.
  const vision::VisionLinkStats& v = *run.vision;
  nlohmann::json j = nlohmann::json::parse(json);
  j["vision"] = {{"requests", v.worker.submitted},
                 {"answered", v.worker.answered},
                 {"succeeded", v.worker.succeeded},
                 {"failed", v.worker.failed},
                 {"expired", v.worker.expired},
                 {"success_rate", v.worker.success_rate()},
                 {"latency_ms_mean", v.worker.latency_ms_mean},
                 {"latency_ms_max", v.worker.latency_ms_max},
                 {"last_failure", v.worker.last_failure},
                 {"without_prior", v.without_prior},
                 {"refused", v.refused},
                 {"cache_misses", v.cache.misses},
                 {"cache_hits", v.cache.hits},
                 {"cache_evictions", v.cache.evictions},
                 {"cache_peak_mb", static_cast<double>(v.cache.peak_bytes) / (1024.0 * 1024.0)}};
  return j.dump();
}

}  // namespace nav::daemon
