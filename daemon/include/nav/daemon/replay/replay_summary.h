#pragma once
// ReplaySummary: what a finished replay reports (summary.json, `navtool replay --json`, navd
// replays), one type in the manner of ceres::Solver::Summary: filled once from the replay
// (make_replay_summary), rendered as the one-line JSON (to_json; keys in README.md "navtool
// replay", sorted as nlohmann::json sorts them) and as a one-line text (brief_report), and read
// back from summary.json by the report (from_json).
//
// LinkOutcomeCounts are the counts of proposed camera pairs by outcome, kept by the filter during
// the replay and counted again from links.csv by the report (nav/report/metrics.h): one type and
// one counting rule for both.

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "nav/core/geometry/types.h"

namespace nav::daemon {

struct ReplayRun;
struct ReplayAnalysis;

/// Proposed camera pairs by outcome (links.csv "outcome", output_schema.h LinksCsv::kOutcomes).
struct LinkOutcomeCounts {
  std::uint64_t proposed = 0;             ///< every proposed pair
  std::uint64_t accepted = 0;             ///< applied as a link
  std::uint64_t gated = 0;                ///< registered, rejected by the chi-square gate
  std::uint64_t registration_failed = 0;  ///< the registration said it failed
  std::uint64_t not_registered = 0;       ///< no registration (in time)
  std::uint64_t outliers_proposed = 0;    ///< pairs whose registration is a simulated outlier
  std::uint64_t outliers_rejected = 0;    ///< ... and not accepted
  std::uint64_t outliers_accepted = 0;    ///< ... and accepted

  /// Counts one proposed pair. Throws std::invalid_argument when `outcome` is not one of
  /// LinksCsv::kOutcomes (the message lists them).
  void add(std::string_view outcome, bool is_outlier);
};

struct ReplaySummary {
  static constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();

  // Inputs.
  std::optional<std::string> dive_dir;  ///< the dive directory (report: where truth.csv is)
  std::string log;                      ///< the dive log replayed
  std::string config;                   ///< the config file used

  // Size of the problem.
  std::uint64_t images = 0;
  std::int64_t delayed_states = 0;  ///< blocks of the final information matrix minus the robot
  std::uint64_t camera_links = 0;   ///< links accepted (the filter's counter)

  // Timing (host clock, s).
  double wall_s = kUnset;           ///< source start to the last measurement filtered
  double log_span_s = kUnset;       ///< host monotonic span of the log
  double realtime_factor = kUnset;  ///< log_span_s / wall_s (0 when wall_s is 0)
  double analysis_s = kUnset;       ///< final analysis (exact marginals, log-det ratios)

  // Estimates: x_m, y_m, z_m, roll_rad, pitch_rad, heading_rad.
  core::Vec6 final_pose = core::Vec6::Zero();    ///< robot, direct solve after the replay
  std::optional<core::Vec6> final_pose_running;  ///< robot, as published (none: no state yet)
  bool has_dead_reckoning = false;               ///< dead reckoning ran (key present when true)
  std::optional<core::Vec6> dead_reckoning_final_pose;  ///< its robot (none: no state yet)
  /// Dead reckoning's rejected_updates (below); key "dead_reckoning_rejected_updates" with it.
  std::map<std::string, std::uint64_t> dead_reckoning_rejected_updates;

  // Recovery.
  double max_cg_relative_residual = kUnset;
  std::int64_t cg_iterations_per_image = 0;
  std::string recovery;  ///< how recovery ran (synchronous or recovery thread), in words

  // Camera links (the filter's counters; outliers_proposed is not part of the summary).
  std::uint64_t candidates = 0;  ///< delayed states considered for a link
  LinkOutcomeCounts links;
  double camera_gate_chi2_5dof = kUnset;
  std::uint64_t registrations = 0;          ///< registrations available to the replay
  std::uint64_t registration_outliers = 0;  ///< of them simulated outliers

  // Link proposal (replay/proposal_recall.h): proposed pairs per image, and the fraction of
  // the pairs whose true footprints overlap >= 20 % that were proposed (simulated dives).
  double proposals_per_image_mean = kUnset;
  double proposal_recall = kUnset;
  // Published covariance against truth (navtool replay with a dive's truth.csv; report
  // published_nees): mean NEES and the fraction above chi2(6, 0.99) of every published pose.
  double published_nees_mean = kUnset;
  double published_nees_exceed_99_fraction = kUnset;

  // The bounds at the time of use (dive_replay.h ReplayOptions::time_of_use_every_images;
  // unset without checks): fractions conservative against the exact marginals of the moment,
  // and the medians of Fig. 3's relative-pose log-det ratio over every (check, state) pair.
  std::uint64_t time_of_use_checks = 0;
  double time_of_use_s = kUnset;  ///< wall time of the checks (not part of wall_s)
  double time_of_use_conservative_fraction = kUnset;        ///< stored bounds
  double time_of_use_joint_conservative_fraction = kUnset;  ///< proposal joints
  /// Smallest eigenvalue of (ours − exact) over every bound and joint checked (< 0: not
  /// conservative; its size says whether by rounding or by a real error).
  double time_of_use_worst_min_eigenvalue = kUnset;
  double logdet_ratio_relative_ours_median = kUnset;
  double logdet_ratio_relative_markov_blanket_median = kUnset;
  // Consistency of the bounds (final analysis).
  double conservative_fraction = kUnset;
  std::uint64_t states_checked = 0;

  // Filter and source counters.
  std::uint64_t measurements = 0, updates = 0, update_failures = 0, recovery_failures = 0;
  std::uint64_t bound_update_failures = 0, before_initialisation = 0;
  std::uint64_t decode_errors = 0, late_dropped = 0, ordering_full_dropped = 0;
  /// Per sensor name: its robot updates not fused (innovation gate, nav/core/navigation/
  /// aid_gate.h, or refused by the ESDF); key "rejected_updates", an object.
  std::map<std::string, std::uint64_t> rejected_updates;

  std::string error;  ///< empty when the replay and the analysis succeeded

  /// The JSON object on one line (no newline). Unset doubles render as null.
  std::string to_json() const;
  /// One line for a log or a terminal, e.g. "replay: 866 images, 866 delayed states, 8195 of
  /// 8633 proposed links accepted, 438 of 438 outliers rejected, conservative 1, 19.7 s wall
  /// (421x real time), ok".
  std::string brief_report() const;
  /// Reads a summary.json text. Keys that are absent, null or of another type keep their
  /// defaults (hand-written or older summaries); throws std::invalid_argument naming `source`
  /// when the text is not a JSON object.
  static ReplaySummary from_json(const std::string& text, const std::string& source);
};

/// The summary of a finished replay and its analysis.
ReplaySummary make_replay_summary(const ReplayRun& run, const ReplayAnalysis& analysis,
                                  const std::string& dive_dir, const std::string& config_path);

}  // namespace nav::daemon
