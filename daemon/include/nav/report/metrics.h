#pragma once
// The report's metrics (metrics.json): trajectory errors against the simulator's truth, NEES of
// the delayed states with their exact marginals, conservativeness of the stored bounds, link
// and outlier counts (Eustice et al., RSS 2005, Sec. V; how each is computed: daemon/src/report/
// README.md).

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <utility>
#include <vector>

#include "nav/report/replay_data.h"

namespace nav::report {

/// Truth pose at t_us, linearly interpolated between the bracketing truth.csv rows (angles
/// along the shorter arc); nothing outside [first, last] t_us. `truth` sorted by time.
std::optional<core::Vec6> truth_pose_at(const std::vector<TimedPose>& truth, long long t_us);

/// Horizontal (x, y) error of an estimated trajectory against interpolated truth.
struct XyError {
  double rms_m = 0.0;        ///< sqrt(mean(dx^2 + dy^2)) over the rows inside the truth span
  double final_m = 0.0;      ///< |(dx, dy)| of the last row inside the truth span
  size_t samples = 0;        ///< rows used
  size_t outside_truth = 0;  ///< rows whose t_us lies outside truth.csv (not used)
};
/// Throws ReportError when no row lies inside the truth span (`what` names the estimate).
XyError xy_error(const std::vector<TimedPose>& estimate, const std::vector<TimedPose>& truth,
                 const std::string& what);

/// Wilson-Hilferty approximation of the chi-square quantile with k degrees of freedom at the
/// standard-normal quantile z (2.5 % low at the lower 2.5 % point for k = 6; 4e-6 relative
/// at k = 600: the report uses k = 6 x number of states).
double chi2_quantile(double k, double z);

/// Two-sided 95 % interval of one chi2(6) sample (exact quantiles, regularised incomplete gamma):
/// the test of the robot-pose NEES.
inline constexpr std::pair<double, double> kChi2Dof6Interval95{1.2373442, 14.4493753};

/// NEES e' E^-1 e of each delayed state's pose error (estimate - truth, angles wrapped) with
/// its exact marginal E (6 dof). The robot pose (the newest delayed state: the highest
/// frame_id with a truth pose) gives ONE chi2(6) sample, tested against kChi2Dof6Interval95;
/// the seed average of that sample is the consistency test (hil-tests/nees-seeds). The mean over
/// all states is a diagnostic only: the smoothed states are strongly correlated through the
/// camera links, so it is not tested against an interval of independent samples.
struct NeesResult {
  std::vector<double> nees;  ///< per state with a truth pose
  double xy_rms_m = 0.0;     ///< XY RMS of the final state means against the same truth poses
  double mean = 0.0;         ///< diagnostic: mean over `nees`
  core::Vec6 component_mean = core::Vec6::Zero();   ///< diagnostic: mean of e_k^2 / E_kk
  long long robot_frame_id = -1;                    ///< the newest state with a truth pose
  double robot_nees = 0.0;                          ///< its e' E^-1 e (one chi2(6) sample)
  core::Vec6 robot_component = core::Vec6::Zero();  ///< its e_k^2 / E_kk (1 dof each)
  size_t without_truth = 0;                         ///< states whose truth pose could not be found
  size_t exact_not_positive_definite = 0;           ///< states skipped: e00..e55 not SPD
};
/// Truth per state: images.csv by frame_id when given, else truth.csv interpolated at t_us.
/// States without a truth pose or with a non-SPD exact marginal are counted and skipped (also in
/// xy_rms_m); ReportError when no state is left.
NeesResult delayed_state_nees(const std::vector<DelayedState>& states,
                              const std::vector<TrueImage>& images,
                              const std::vector<TimedPose>& truth);

/// NEES e' P^-1 e (6 dof, e = published pose - truth interpolated at t_us, angles wrapped) of
/// every published solution (published.csv) with its published covariance P: the test that
/// the covariance navd publishes between images is honest. Rows outside truth or with a P
/// that is not positive definite are counted and skipped.
struct PublishedNees {
  size_t samples = 0, outside_truth = 0, not_positive_definite = 0;
  double mean = 0.0;
  double exceed_99_fraction = 0.0;  ///< fraction above chi2(6, 0.99) = kChi2Dof6Quantile99
  /// Mean of e_k² / P_kk per component (x, y, z, roll, pitch, heading): 1 each if consistent;
  /// says which part of the published covariance is over-confident.
  core::Vec6 component_mean = core::Vec6::Zero();
};
inline constexpr double kChi2Dof6Quantile99 = 16.811894;
PublishedNees published_nees(const std::vector<daemon::PublishedSolution>& published,
                             const std::vector<TimedPose>& truth);

/// How many stored bounds are conservative: bound - exact PSD (core/recovery/consistency.h,
/// relative tolerance `tol`), and the worst smallest eigenvalue of bound - exact.
struct ConservativeResult {
  size_t checked = 0;
  size_t conservative = 0;
  double worst_min_eigenvalue = 0.0;
  double fraction() const { return checked ? static_cast<double>(conservative) / checked : 0.0; }
};
ConservativeResult conservative_bounds(const std::vector<DelayedState>& states, double tol);

/// Counts over links.csv: the outcome counts of the replay summary (one counting rule,
/// daemon::LinkOutcomeCounts::add) and the distinct accepted pairs.
struct LinkCounts : daemon::LinkOutcomeCounts {
  size_t camera_links = 0;  ///< distinct accepted (state_i, state_j) pairs
};
LinkCounts count_links(const std::vector<ProposedLink>& links);

struct MetricsOptions {
  double conservative_tolerance = 1e-9;  ///< relative tolerance of the PSD check
};

/// Everything in metrics.json. `dive` may be null (no truth: error metrics are null).
nlohmann::json compute_metrics(const ReplayOutput& replay, const DiveData* dive,
                               const MetricsOptions& options);

}  // namespace nav::report
