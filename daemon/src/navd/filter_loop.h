#pragma once
// The filter thread: the only owner of the Esdf. Pops measurements from the MeasurementQueue,
// releases them in time-of-validity order (TimeOrderingBuffer, latency window from the config),
// and runs the ESDF on the simulated survey:
//
// * a measurement valid at t first advances the filter to t: each step predicts with the
//   survey's known control (core/sim/survey.h predicted_mean), keeping the current robot as a
//   delayed state when an ImageEvent arrived at the step's start (one delayed state per image);
// * DVL, attitude/heading and depth update the robot block with the survey's models and noise;
// * when a step is complete (before the next prediction, and at the end) its camera links are
//   applied between the images' delayed states (the survey stands in for the vision pipeline);
//   then a snapshot of (Λ, η) and the step's prediction records go to the recovery thread;
// * at the end of each step the robot's linearisation point is relinearised in O(1): one block
//   Gauss-Seidel solve  μ_r = Λ_rr⁻¹ (η_r − Σ_j Λ_rj μ_j)  over its few neighbours (the robot's
//   conditional mean given the delayed states), so the robot tracks its measurements even when
//   recovery lags;
// * the newest recovered mean (never waited for) becomes the linearisation point of the delayed
//   states that were in its snapshot.
// systemd: READY=1 once initialised, WATCHDOG=1 at the watchdog period, STATUS= once a second.

#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "nav/core/filter/esdf.h"
#include "nav/core/sim/survey.h"
#include "nav/daemon/measurement_queue.h"
#include "nav/daemon/sd_notify.h"
#include "nav/daemon/time_ordering.h"
#include "navd/mailboxes.h"

namespace nav::navd {

struct FilterCounters {
  std::uint64_t steps = 0;
  std::uint64_t images = 0;
  std::uint64_t camera_links = 0;
  std::uint64_t updates = 0;
  std::uint64_t update_failures = 0;         ///< rejected by the filter (Status not ok)
  std::uint64_t unmatched_measurements = 0;  ///< valid at a time that is no survey step end
  std::uint64_t recoveries_applied = 0;
};

struct FilterLoopResult {
  FilterCounters counters;
  daemon::TimeOrderingStats ordering;
  bool completed = false;  ///< every survey step was applied
  /// ‖p̂ − p_true‖ at the last applied step: running estimate, and after a direct mean solve.
  double final_position_error_m = 0.0;
  double final_position_error_running_m = 0.0;
  double survey_time_s = 0.0;  ///< survey time reached
  std::string error;           ///< non-empty if the filter stopped on an error
};

class FilterLoop {
 public:
  FilterLoop(const core::sim::Survey& survey, daemon::MeasurementQueue& queue,
             const daemon::TimeOrderingOptions& ordering, RecoveryInbox& inbox,
             RecoveryOutbox& outbox, SolutionBoard& board, const daemon::SdNotifier& notifier);

  /// Runs until the source is done and everything is applied, or `stop` is set.
  FilterLoopResult run(const std::atomic<bool>& stop, const std::atomic<bool>& source_done);

 private:
  bool initialise();
  void drain_queue();
  void process(const daemon::Measurement& m);
  void advance_to(std::int64_t t_us);
  void predict_step();
  void finish_step();
  void apply_recovery();
  void relinearise_robot();
  void update_robot(const daemon::Measurement& m);
  void apply_links(const core::sim::SurveyStep& step);
  void publish_view();
  void notify_systemd(bool force_status);
  std::string status_line() const;
  FilterLoopResult finish(bool completed);
  void fail(const std::string& where, const core::Status& s);

  const core::sim::Survey& survey_;
  daemon::MeasurementQueue& queue_;
  daemon::TimeOrderingBuffer ordering_;
  RecoveryInbox& inbox_;
  RecoveryOutbox& outbox_;
  SolutionBoard& board_;
  const daemon::SdNotifier& notifier_;

  core::Esdf filter_{12};
  std::vector<std::int64_t> step_start_us_;
  std::vector<int> image_blocks_;  ///< image index -> delayed block (-1 if not kept)
  std::vector<daemon::Measurement> batch_;
  std::vector<PredictionRecord> records_;  ///< predictions since the last snapshot
  size_t next_step_ = 0;                   ///< survey step to predict next
  bool step_open_ = false;                 ///< a predicted step awaits finish_step()
  int pending_image_ = -1;                 ///< image at the start of the next step
  FilterCounters counters_;
  double last_residual_ = 0.0;
  int last_iterations_ = 0;
  std::string error_;
  std::int64_t last_watchdog_us_ = 0;
  std::int64_t last_status_us_ = 0;
};

}  // namespace nav::navd
