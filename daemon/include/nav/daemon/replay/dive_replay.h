#pragma once
// Replay of a recorded dive through the same code as navd on the vehicle (hil-tests/README.md):
// dive-log source thread (run_dive_log_source: RAW_* through the sensor decoders, NAV_IMAGE) ->
// MeasurementQueue -> TimeOrderingBuffer (filter.latency_window_ms) -> NavFilter, plus a
// DeadReckoningFilter fed the same measurements (the robot alone, no camera links). Registrations
// (NAV_REGISTRATION) are read before the replay (load_registrations), as the vision stage's
// stand-in; with vision.enabled navd registers the dive's frames itself instead, answers applied
// at data times (vision/vision_link.h), so the output is deterministic too.
//
// Recovery: the configured fixed PCG iterations (filter.cg_iterations_per_step per image)
// synchronously at each image, or with filter.recovery_thread on NavFilter's recovery thread,
// whose results the filter takes at data times (filter.recovery_handoff_s; nav_filter.h
// "Recovery thread"); either way the result does not depend on thread timing: as
// fast as possible, the same log and config give the same output. Dead reckoning runs on a
// thread of its own (FilterWorker), in covariance form (core/navigation/dead_reckoning.h).
//
// Time of use (ReplayOptions::time_of_use_every_images): at chosen images, before their link
// proposal, the bounds and proposal joints against the exact marginals of that moment.
//
// After the replay, analyse() computes what the replay output files need: the final mean
// (direct solve), exact marginals (CHOLMOD + Takahashi), bound-vs-exact checks, and the Fig. 3
// log-det ratios (ours and Markov blanket, robot vs every delayed state).

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "nav/core/navigation/dead_reckoning.h"
#include "nav/core/navigation/nav_filter.h"
#include "nav/core/navigation/registration_table.h"
#include "nav/core/recovery/time_of_use.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/filter/registration_message.h"
#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/queue/time_ordering.h"
#include "nav/daemon/sources/dive_log_source.h"
#include "nav/daemon/vision/vision_link.h"

namespace nav::daemon {

struct ReplayOptions {
  double speed = 1.0;               ///< x real time (> 0) unless as_fast_as_possible
  bool as_fast_as_possible = true;
  std::size_t queue_capacity = 4096;
  bool dead_reckoning = true;  ///< also run dead reckoning (no camera links)
  /// Called on the filter thread after each measurement the SLAM filter processed (navd
  /// publishes from here); must be quick.
  std::function<void(const NavFilter&)> after_measurement;
  /// Use this queue instead of an own one (navd's publisher reports its depth); not owned.
  MeasurementQueue* queue = nullptr;
  /// Set to stop the replay early (signal); the output is what was filtered so far.
  const std::atomic<bool>* stop = nullptr;
  /// navd: checkpoint the SLAM filter (config.checkpoint: path, period_s, keep; payload tagged
  /// with the log path) and resume from the newest valid checkpoint of this log, skipping the
  /// measurements it holds (filter/nav_filter_checkpointer.h). Dead reckoning is not
  /// checkpointed: it is fed every measurement, skipped or not.
  bool checkpoints = false;
  /// Input identity written into and required of the checkpoints ("": the log path). navd's
  /// default mode names the simulated dive and its options, so that a dive simulated again at
  /// the same path never resumes a checkpoint of the previous one.
  std::string checkpoint_identity;
  /// Check the bounds at the time of use at every k-th image (1st, k+1-th, ...), right before
  /// its link proposal (core/recovery/time_of_use.h); 0: never. A check costs exact marginals
  /// of the whole map: its time is kept off the replay's clock (ReplayRun::time_of_use_s).
  int time_of_use_every_images = 0;
  bool time_of_use_markov_blanket = false;  ///< the checks include the Markov blanket's ratios
};

/// The robot's solution as navd publishes it (NAVD_SOLUTION): the mean and the current
/// covariance (NavFilter::robot_covariance) of the pose at the filter's time.
struct PublishedSolution {
  std::int64_t t_us = 0;
  core::Vec6 pose = core::Vec6::Zero();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
};

struct ReplayRun {
  std::string log_path;
  std::unique_ptr<RegistrationTable> registrations;
  std::unique_ptr<NavFilter> slam;
  std::unique_ptr<core::DeadReckoningFilter>
      dead_reckoning;  ///< null unless options.dead_reckoning
  DiveLogSourceCounters source;
  TimeOrderingStats ordering;
  double wall_s = 0.0;      ///< source start to the last measurement filtered
  double log_span_s = 0.0;  ///< host monotonic span of the log
  std::string error;        ///< non-empty: the filter or the source failed (what, where)
  std::string resumed_from;             ///< checkpoint file resumed ("" if none)
  std::uint64_t resumed_measurements = 0;  ///< measurements that checkpoint held (skipped)
  /// vision.enabled: navd registered the frames itself (vision/vision_link.h) instead of
  /// reading the log's registrations; its counters at the end.
  std::optional<vision::VisionLinkStats> vision;
  std::vector<vision::AppliedAnswer> vision_answers;  ///< every answer applied, in order
  /// The SLAM filter's solution every 1/lcm.channels.nav_solution.rate_hz of data time (the
  /// first measurement at or after each period), as navd would publish it (published.csv).
  std::vector<PublishedSolution> published;
  /// ReplayOptions::time_of_use_every_images: the checks, the frame id of each check's image
  /// (time_of_use_frames[c - 1] for TimeOfUsePair::check c) and their wall time, which wall_s
  /// does not include.
  core::TimeOfUseStats time_of_use;
  std::vector<std::uint64_t> time_of_use_frames;
  double time_of_use_s = 0.0;
};

/// Plays `log_path` through the filters. Throws DiveLogError / ConfigError / invalid_argument
/// on unusable inputs; a filter failure mid-replay is reported in ReplayRun::error.
ReplayRun run_replay(const std::string& log_path, const NavdConfig& config,
                     const ReplayOptions& options);

struct StateCheck {  ///< one delayed state at the end (states.csv)
  int state = -1;
  const ImageRecord* image = nullptr;
  core::Vec12 mean = core::Vec12::Zero();   ///< final mean (direct solve)
  Eigen::Matrix<double, 6, 6> bound, exact, initial_bound;  ///< pose parts
  bool conservative = false;
};

struct LogdetRow {  ///< logdet.csv
  int state_i = 0, state_j = 0;
  double ours = 0.0, markov_blanket = 0.0;
};

struct ReplayAnalysis {
  std::vector<StateCheck> states;
  std::vector<LogdetRow> logdet;
  core::Vec12 robot_mean = core::Vec12::Zero();  ///< final robot, direct solve
  double conservative_fraction = 0.0;
  double analysis_s = 0.0;
  std::string error;
};

/// Final analysis of the SLAM filter (runs one more recovery step so the robot column is
/// current; the filter is otherwise unchanged).
ReplayAnalysis analyse(NavFilter& slam);

struct ReplaySummary;
/// The JSON summary (one line): summary.to_json() (replay_summary.h; keys listed in README.md
/// "navtool replay"), with run.vision's counters as "vision" when navd registered the frames.
std::string replay_summary_json(const ReplaySummary& summary, const ReplayRun& run);

/// Writes every file of hil-tests/README.md "Replay output directory" into `dir` (created), with
/// the writers of output_files.h. Throws std::runtime_error naming the file that cannot be
/// written.
void write_replay_outputs(const ReplayRun& run, const ReplayAnalysis& analysis,
                          const std::string& summary_json, const std::string& dir);

}  // namespace nav::daemon
