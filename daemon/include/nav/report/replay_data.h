#pragma once
// Typed contents of a dive directory and a replay output directory (formats fixed in
// hil-tests/README.md: "A dive directory", "Replay output directory"). Readers check every
// column they use and name file:line on a bad value; optional files and columns are marked.

#include <Eigen/Core>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/daemon/replay/dive_replay.h"
#include "nav/daemon/replay/replay_summary.h"

namespace nav::report {

/// One row of truth.csv / trajectory.csv / dead_reckoning.csv (position in world NED, m).
struct TimedPose {
  long long t_us = 0;
  core::Vec6 pose = core::Vec6::Zero();  ///< x y z roll pitch heading (m, rad)
};

/// images.csv: the true vehicle pose at each image's time of validity.
struct TrueImage {
  long long frame_id = 0;
  long long t_us = 0;
  core::Vec6 pose = core::Vec6::Zero();
};

/// states.csv: one delayed state at the end of the replay.
struct DelayedState {
  long long state_id = 0;
  long long frame_id = 0;
  long long t_us = 0;
  core::Vec6 pose = core::Vec6::Zero();   ///< final recovered mean
  core::Mat6 bound = core::Mat6::Zero();  ///< stored conservative bound (b00..b55)
  core::Mat6 exact = core::Mat6::Zero();  ///< exact marginal (e00..e55)
  std::optional<core::Mat6> initial;      ///< bound at insertion (i00..i55), when written
};

/// links.csv: one proposed pair.
struct ProposedLink {
  long long t_us = 0;
  long long frame_i = 0, frame_j = 0;
  long long state_i = 0, state_j = 0;
  std::string outcome;  ///< accepted, gated, registration_failed, not_registered
  double mahalanobis_sq = 0.0;
  bool is_outlier = false;
};

/// logdet.csv: log(det approx / det exact) of one relative-pose covariance.
struct LogdetRow {
  long long state_i = 0, state_j = 0;
  double ours = 0.0;
  double markov_blanket = 0.0;
};

/// time_of_use.csv: Fig. 3's ratios of one (check, state) pair at the time of use.
struct TimeOfUseRow {
  long long frame_id = 0;  ///< the image checked, before its link proposal
  long long state = 0;
  double ours = 0.0;
  double markov_blanket = 0.0;  ///< NaN when not computed
};

/// information_blocks.csv: the block sparsity pattern of the final information matrix.
struct BlockPattern {
  int block_dim = 0;
  long long num_blocks = 0;
  std::vector<std::pair<long long, long long>> blocks;  ///< (i, j), i <= j
};

/// The replay output directory. Files marked optional are empty/absent-tolerant.
struct ReplayOutput {
  std::filesystem::path dir;
  daemon::ReplaySummary summary;          ///< summary.json (defaults when absent)
  std::vector<TimedPose> trajectory;      ///< trajectory.csv
  std::vector<TimedPose> dead_reckoning;  ///< dead_reckoning.csv
  std::vector<DelayedState> states;       ///< states.csv
  std::vector<ProposedLink> links;        ///< links.csv
  long long proposal_rows = 0;            ///< proposals.csv rows (optional file)
  long long proposed = 0;                 ///< proposals.csv: sum of proposed
  long long true_overlapping = 0;         ///< ... of true_overlapping (0 when absent)
  long long true_overlapping_proposed = 0;  ///< ... of true_overlapping_proposed
  std::vector<daemon::PublishedSolution> published;  ///< published.csv (optional)
  std::optional<BlockPattern> blocks;     ///< information_blocks.csv (optional)
  std::vector<LogdetRow> logdet;          ///< logdet.csv (optional)
  std::vector<TimeOfUseRow> time_of_use;  ///< time_of_use.csv (optional)
};

/// The simulated dive directory (all parts optional except truth.csv).
struct DiveData {
  std::filesystem::path dir;
  std::vector<TimedPose> truth;   ///< truth.csv, sorted by t_us
  std::vector<TrueImage> images;  ///< images.csv (empty when absent)
  nlohmann::json sim;             ///< sim.json ({} when absent)
};

/// Reads the replay output directory. trajectory.csv, dead_reckoning.csv, states.csv and
/// links.csv are required; the others are read when present. Throws ReportError.
ReplayOutput read_replay_output(const std::filesystem::path& dir);
/// Reads the dive directory (truth.csv required). Throws ReportError.
DiveData read_dive(const std::filesystem::path& dir);

// Single-file readers (used by the above; exposed for tests).
std::vector<TimedPose> read_timed_poses(const std::filesystem::path& file);
std::vector<TrueImage> read_images(const std::filesystem::path& file);
std::vector<DelayedState> read_states(const std::filesystem::path& file);
std::vector<ProposedLink> read_links(const std::filesystem::path& file);
BlockPattern read_block_pattern(const std::filesystem::path& file);
std::vector<LogdetRow> read_logdet(const std::filesystem::path& file);
std::vector<TimeOfUseRow> read_time_of_use(const std::filesystem::path& file);
std::vector<daemon::PublishedSolution> read_published(const std::filesystem::path& file);
daemon::ReplaySummary read_summary(const std::filesystem::path& file);
nlohmann::json read_json(const std::filesystem::path& file);

}  // namespace nav::report
