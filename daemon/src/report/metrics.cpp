// Report metrics: see metrics.h and daemon/src/report/README.md.
#include "nav/report/metrics.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "nav/core/geometry/pose.h"
#include "nav/core/geometry/rotation.h"
#include "nav/core/recovery/consistency.h"
#include "nav/daemon/replay/output_schema.h"
#include "nav/report/csv_table.h"

namespace nav::report {
namespace {

using nlohmann::json;

json or_null(const std::optional<double>& v) { return v ? json(*v) : json(nullptr); }

std::optional<double> json_number(const json& j, const char* key) {
  if (j.is_object() && j.contains(key) && j[key].is_number()) return j[key].get<double>();
  return std::nullopt;
}

/// A summary number, or nothing when summary.json did not give it (ReplaySummary::kUnset).
std::optional<double> set_or_none(double v) {
  return std::isnan(v) ? std::nullopt : std::optional<double>(v);
}

/// Duration of the dive, s: sim.json duration_s, else the span of truth.csv.
std::optional<double> dive_duration_s(const DiveData* dive) {
  if (!dive) return std::nullopt;
  if (auto d = json_number(dive->sim, "duration_s")) return d;
  return 1e-6 * static_cast<double>(dive->truth.back().t_us - dive->truth.front().t_us);
}

/// {x, y, z, roll, pitch, heading} of a pose-sized vector.
json component_json(const core::Vec6& v) {
  return {{"x", v[0]},    {"y", v[1]},     {"z", v[2]},
          {"roll", v[3]}, {"pitch", v[4]}, {"heading", v[5]}};
}

}  // namespace

std::optional<core::Vec6> truth_pose_at(const std::vector<TimedPose>& truth, long long t_us) {
  if (truth.empty() || t_us < truth.front().t_us || t_us > truth.back().t_us) return std::nullopt;
  const auto hi = std::lower_bound(truth.begin(), truth.end(), t_us,
                                   [](const TimedPose& p, long long t) { return p.t_us < t; });
  if (hi->t_us == t_us || hi == truth.begin()) return hi->pose;
  const auto lo = hi - 1;
  const double a = static_cast<double>(t_us - lo->t_us) / static_cast<double>(hi->t_us - lo->t_us);
  // pose_minus wraps the angle differences, so angles move along the shorter arc.
  core::Vec6 p = lo->pose + a * core::pose_minus(hi->pose, lo->pose);
  for (int k = 3; k < 6; ++k) p[k] = core::wrap_angle(p[k]);
  return p;
}

XyError xy_error(const std::vector<TimedPose>& estimate, const std::vector<TimedPose>& truth,
                 const std::string& what) {
  XyError e;
  double sum_sq = 0.0;
  for (const TimedPose& row : estimate) {
    const auto t = truth_pose_at(truth, row.t_us);
    if (!t) {
      ++e.outside_truth;
      continue;
    }
    const double err_sq = (row.pose.head<2>() - t->head<2>()).squaredNorm();
    sum_sq += err_sq;
    e.final_m = std::sqrt(err_sq);
    ++e.samples;
  }
  if (e.samples == 0) {
    throw ReportError(what + ": none of its " + std::to_string(estimate.size()) +
                      " rows lies inside the time span of truth.csv");
  }
  e.rms_m = std::sqrt(sum_sq / static_cast<double>(e.samples));
  return e;
}

double chi2_quantile(double k, double z) {
  const double c = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - c + z * std::sqrt(c), 3.0);
}

NeesResult delayed_state_nees(const std::vector<DelayedState>& states,
                              const std::vector<TrueImage>& images,
                              const std::vector<TimedPose>& truth) {
  std::map<long long, core::Vec6> by_frame;
  for (const TrueImage& im : images) by_frame[im.frame_id] = im.pose;
  NeesResult r;
  double sum_xy_sq = 0.0;
  for (const DelayedState& s : states) {
    std::optional<core::Vec6> true_pose;
    if (!images.empty()) {
      if (auto it = by_frame.find(s.frame_id); it != by_frame.end()) true_pose = it->second;
    } else {
      true_pose = truth_pose_at(truth, s.t_us);
    }
    if (!true_pose) {
      ++r.without_truth;
      continue;
    }
    const core::Vec6 err = core::pose_minus(s.pose, *true_pose);
    const Eigen::LLT<core::Mat6> llt(0.5 * (s.exact + s.exact.transpose()));
    if (llt.info() != Eigen::Success) {  // counted, not fatal: the other states still tell
      ++r.exact_not_positive_definite;
      continue;
    }
    const core::Vec6 component = err.array().square() / s.exact.diagonal().array();
    r.nees.push_back(err.dot(llt.solve(err)));
    r.component_mean += component;
    sum_xy_sq += err.head<2>().squaredNorm();
    if (s.frame_id > r.robot_frame_id) {
      r.robot_frame_id = s.frame_id;
      r.robot_nees = r.nees.back();
      r.robot_component = component;
    }
  }
  if (r.nees.empty()) {
    throw ReportError("NEES: no delayed state has a truth pose (" + std::to_string(states.size()) +
                      " states)");
  }
  const double n = static_cast<double>(r.nees.size());
  double sum = 0.0;
  for (double v : r.nees) sum += v;
  r.mean = sum / n;
  r.component_mean /= n;
  r.xy_rms_m = std::sqrt(sum_xy_sq / n);
  return r;
}

ConservativeResult conservative_bounds(const std::vector<DelayedState>& states, double tol) {
  ConservativeResult r;
  bool first = true;
  for (const DelayedState& s : states) {
    double min_eig = 0.0;
    const bool ok = core::is_conservative(s.bound, s.exact, tol, &min_eig);
    ++r.checked;
    if (ok) ++r.conservative;
    r.worst_min_eigenvalue = first ? min_eig : std::min(r.worst_min_eigenvalue, min_eig);
    first = false;
  }
  return r;
}

PublishedNees published_nees(const std::vector<daemon::PublishedSolution>& published,
                             const std::vector<TimedPose>& truth) {
  PublishedNees out;
  size_t exceed = 0;
  double sum = 0.0;
  for (const daemon::PublishedSolution& p : published) {
    const std::optional<core::Vec6> t = truth_pose_at(truth, p.t_us);
    if (!t) {
      ++out.outside_truth;
      continue;
    }
    const Eigen::LLT<core::Mat6> llt(p.covariance);
    if (llt.info() != Eigen::Success) {
      ++out.not_positive_definite;
      continue;
    }
    const core::Vec6 e = core::pose_minus(p.pose, *t);
    const double nees = e.dot(llt.solve(e));
    sum += nees;
    out.component_mean += e.cwiseAbs2().cwiseQuotient(p.covariance.diagonal());
    exceed += nees > kChi2Dof6Quantile99 ? 1 : 0;
    ++out.samples;
  }
  if (out.samples > 0) {
    out.mean = sum / static_cast<double>(out.samples);
    out.exceed_99_fraction = static_cast<double>(exceed) / static_cast<double>(out.samples);
    out.component_mean /= static_cast<double>(out.samples);
  }
  return out;
}

LinkCounts count_links(const std::vector<ProposedLink>& links) {
  LinkCounts c;
  std::set<std::pair<long long, long long>> pairs;
  for (const ProposedLink& l : links) {
    c.add(l.outcome, l.is_outlier);  // outcomes were checked by read_links
    if (l.outcome == daemon::output_schema::LinksCsv::kOutcomes[0]) {  // accepted
      pairs.emplace(std::min(l.state_i, l.state_j), std::max(l.state_i, l.state_j));
    }
  }
  c.camera_links = pairs.size();
  return c;
}

json compute_metrics(const ReplayOutput& replay, const DiveData* dive,
                     const MetricsOptions& options) {
  json m;
  const LinkCounts links = count_links(replay.links);
  // Images of the dive: images.csv rows, else sim.json "images", else proposals.csv rows.
  json images = nullptr;
  if (dive && !dive->images.empty()) {
    images = dive->images.size();
  } else if (dive && json_number(dive->sim, "images")) {
    images = dive->sim["images"];
  } else if (replay.proposal_rows > 0) {
    images = replay.proposal_rows;
  }
  m["images"] = images;
  m["delayed_states"] = replay.states.size();
  m["camera_links"] = links.camera_links;
  m["links_proposed"] = links.proposed;
  m["links_accepted"] = links.accepted;
  m["links_gated"] = links.gated;
  m["links_registration_failed"] = links.registration_failed;
  m["links_not_registered"] = links.not_registered;
  m["outliers_injected"] = dive && json_number(dive->sim, "outliers_injected")
                               ? dive->sim["outliers_injected"]
                               : json(nullptr);
  m["outliers_proposed"] = links.outliers_proposed;
  m["outliers_rejected"] = links.outliers_rejected;
  m["outliers_accepted"] = links.outliers_accepted;

  if (dive) {
    const XyError dr = xy_error(replay.dead_reckoning, dive->truth, "dead_reckoning.csv");
    const XyError slam = xy_error(replay.trajectory, dive->truth, "trajectory.csv");
    m["dr_xy_rms_m"] = dr.rms_m;
    m["dr_final_xy_error_m"] = dr.final_m;
    m["slam_xy_rms_m"] = slam.rms_m;
    m["slam_final_xy_error_m"] = slam.final_m;
    m["xy_error_samples"] = {{"dead_reckoning", dr.samples}, {"slam", slam.samples}};
    m["xy_error_rows_outside_truth"] = {{"dead_reckoning", dr.outside_truth},
                                        {"slam", slam.outside_truth}};
    if (!replay.states.empty()) {
      const NeesResult nees = delayed_state_nees(replay.states, dive->images, dive->truth);
      m["states_xy_rms_m"] = nees.xy_rms_m;
      // The robot pose: one chi2(6) sample per dive (nees_samples 1), seed-averaged by
      // hil-tests/nees-seeds; the all-states mean is a diagnostic (metrics.h NeesResult).
      const auto [lo, hi] = kChi2Dof6Interval95;
      m["nees_mean"] = nees.robot_nees;
      m["nees_95_interval"] = {lo, hi};
      m["nees_within_interval"] = nees.robot_nees >= lo && nees.robot_nees <= hi;
      m["nees_samples"] = 1;
      m["nees_dof_per_state"] = core::kPoseDim;
      m["nees_robot_pose"] = {{"frame_id", nees.robot_frame_id},
                              {"nees", nees.robot_nees},
                              {"components", component_json(nees.robot_component)}};
      m["nees_all_states_diagnostic"] = {
          {"mean", nees.mean},
          {"states", nees.nees.size()},
          {"component_means", component_json(nees.component_mean)},
          {"note", "correlated smoothed states: not an independent-sample test, no interval"}};
      m["nees_states_without_truth"] = nees.without_truth;
      m["nees_states_exact_not_positive_definite"] = nees.exact_not_positive_definite;
    }
  }
  m["proposals_per_image_mean"] =
      replay.proposal_rows > 0
          ? json(static_cast<double>(replay.proposed) / static_cast<double>(replay.proposal_rows))
          : json(nullptr);
  m["proposal_recall"] = replay.true_overlapping > 0
                             ? json(static_cast<double>(replay.true_overlapping_proposed) /
                                    static_cast<double>(replay.true_overlapping))
                             : json(nullptr);
  m["published_nees_mean"] = nullptr;
  m["published_nees_exceed_99_fraction"] = nullptr;
  m["published_nees_component_mean"] = nullptr;
  if (dive && !replay.published.empty()) {
    const PublishedNees nees = published_nees(replay.published, dive->truth);
    if (nees.samples > 0) {
      m["published_nees_mean"] = nees.mean;
      m["published_nees_exceed_99_fraction"] = nees.exceed_99_fraction;
      m["published_nees_component_mean"] = component_json(nees.component_mean);
    }
    m["published_nees_samples"] = nees.samples;
  }
  for (const char* key :
       {"dr_xy_rms_m", "slam_xy_rms_m", "slam_final_xy_error_m", "nees_mean", "nees_95_interval"}) {
    if (!m.contains(key)) m[key] = nullptr;
  }

  const ConservativeResult cons =
      conservative_bounds(replay.states, options.conservative_tolerance);
  m["conservative_fraction"] = cons.checked ? json(cons.fraction()) : json(nullptr);
  m["conservative_checked"] = cons.checked;
  m["conservative_worst_min_eigenvalue"] =
      cons.checked ? json(cons.worst_min_eigenvalue) : json(nullptr);
  m["conservative_tolerance"] = options.conservative_tolerance;

  const std::optional<double> wall_s = set_or_none(replay.summary.wall_s);
  std::optional<double> rtf = set_or_none(replay.summary.realtime_factor);
  if (!rtf && wall_s && *wall_s > 0.0) {
    if (auto d = dive_duration_s(dive)) rtf = *d / *wall_s;
  }
  m["wall_s"] = or_null(wall_s);
  m["realtime_factor"] = or_null(rtf);
  m["dive_duration_s"] = or_null(dive_duration_s(dive));
  return m;
}

}  // namespace nav::report
