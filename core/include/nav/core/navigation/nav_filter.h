#pragma once
// NavFilter: the view-based SLAM filter on measurements (Eustice, Singh, Leonard, Walter &
// Ballard, "Visually Navigating the RMS Titanic with SLAM Information Filters", RSS 2005), on
// the exactly sparse delayed-state filter (Eustice, Singh & Leonard, "Exactly Sparse
// Delayed-State Filters", ICRA 2005). Owns the ESDF (12-element blocks), the state recovery
// (fixed-iteration PCG) and the Algorithm 1 bounds; composes the aid sources (aid_sources.h),
// link proposal and gate (link_gate.h), pending registrations (pending_registrations.h) and
// the recovery schedule (recovery_executor.h).
//
// Contract: measurements arrive in time-of-validity order (one older than the newest processed
// is counted out_of_order and skipped). Work per measurement is O(1) in the map size, per image
// O(map). Not thread-safe (one owner thread; a recovery executor touches only its snapshot).
// Algorithm:
// * Initialisation: measurements are held until a roll/pitch, a heading and a depth have been
//   seen; the filter then starts at the FIRST held measurement's time (the world origin) with
//   x = y = 0 (initial_xy_sigma_m), z from the depth minus the lever arm, attitude from the
//   attitude sensor (priors 10x the sensor sigmas), velocities and rates 0 with loose priors,
//   and every held measurement is processed. Beyond 1024 held they are dropped (counted).
// * Predict: constant-velocity model to each measurement's time in equal steps of at most
//   max_predict_step_s; one less than min_predict_step_s after the filter's time is applied at
//   that time. The steps and the held step are shared with dead reckoning
//   (robot_prediction.h). Before each
//   prediction the robot is relinearised in O(1) at its conditional mean given its neighbours: μ_r
//   = Λ_rr⁻¹(η_r − Σ_j Λ_rj μ_j) (angles not wrapped: μ must stay on the branch η encodes). A step
//   the model cannot take (pitch beyond +-89.5 deg) is held instead (robot_prediction.h: attitude
//   and rates treated as lost, counted in predictions_held): the filter goes on.
// * Update: each aid source's observation passes its innovation gate (aid_gate.h: NIS against
//   a chi-square gate, runs of rejections, reset after a timeout; a rejected one changes
//   nothing and is counted in innovations()) and is fused into the ESDF and, as a Kalman update
//   of B_rr, into the robot bound (still an upper bound of Σ_rr), so the bound stored for each
//   new delayed state stays tight.
// * Image at t: predict to t; extend the warm start across everything since the last recovery
//   (warm_start_tracker.h); recovery_.iterations_per_step PCG iterations on the current Λ, η
//   (or, with a recovery executor, the true residual of the previous job's extended result:
//   the certificate the bounds need); hand it to the bounds (certified, bounds.h); evaluate
//   the link hypothesis from the robot (= this image) to every earlier delayed state and
//   propose the most probable ones, at most proposal.max_per_image (link_proposer.h); look each
//   pair up in the RegistrationTable, gate it and apply accepted links to the ESDF and to Σ~_ii
//   (bounds update, constant time). The next prediction keeps the robot as this image's delayed
//   state.
// * Recovery executor (recovery_thread): after the prediction that keeps the image's state the
//   filter submits a job on a snapshot of Λ, η and the warm start, and takes its result at
//   data time t + recovery_handoff_s, the next image or finish(): the warm start becomes the
//   result (A and P replayed from its Σ_tt, warm_start_tracker.h), its exact marginals reset
//   the bounds, the snapshot's delayed states take its mean. Outputs are deterministic.
// * Published solution (robot_mean(), robot_covariance()): the covariance is the certified robot
//   bound B_rr of bounds.h, propagated with every prediction (F B Fᵀ + Q), Kalman-updated with
//   every DVL, heading, depth and attitude measurement (a constant-time 12x12 recursion), reset
//   to the recovered Σ_rr plus its certified error at each image and updated with its links: so
//   it is current and >= Σ_rr whatever the PCG budget (bounds.h GUARANTEE), = Σ_rr with an exact
//   recovery and no link since the last image. The mean is the robot's conditional mean after
//   every update (the ESDF's robot mean is the last prediction's linearisation point: it lags).

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "nav/core/filter/esdf.h"
#include "nav/core/models/constant_velocity.h"
#include "nav/core/navigation/aid_sources.h"
#include "nav/core/navigation/initial_state.h"
#include "nav/core/navigation/innovation_stats.h"
#include "nav/core/navigation/link_gate.h"
#include "nav/core/navigation/link_proposer.h"
#include "nav/core/navigation/nav_filter_options.h"
#include "nav/core/navigation/nav_filter_records.h"
#include "nav/core/navigation/pending_registrations.h"
#include "nav/core/navigation/recovery_executor.h"
#include "nav/core/navigation/registration_table.h"
#include "nav/core/navigation/sensor_measurements.h"
#include "nav/core/navigation/sensor_models.h"
#include "nav/core/navigation/warm_start_tracker.h"
#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/state_recovery.h"
#include "nav/core/status.h"

namespace nav::core {

class NavFilter {
 public:
  /// `registrations` may be null (then every proposal is not registered); it must outlive the
  /// filter. Throws std::invalid_argument for invalid options or camera calibration.
  NavFilter(NavFilterOptions options, const RegistrationTable* registrations);

  /// Processes one measurement (time-ordered). Returns an error only when the filter itself
  /// fails (prediction breakdown); a rejected measurement is counted instead.
  Status process(const Measurement& m);
  /// End of data: takes the job in flight, expires pending pairs, keeps a pending image as a
  /// delayed state (a 0.1 s prediction) and takes that state's job.
  Status finish();
  /// One recovery now (as at an image, without link proposal), e.g. before a final analysis;
  /// false if it failed (counted). With an executor: takes the job in flight, runs one job on
  /// the current Λ and takes it.
  bool recover_now();
  /// A recovery job is in flight (submitted, not yet taken).
  bool recovery_in_flight() const { return jobs_.in_flight(); }

  bool initialised() const { return initialised_; }
  std::int64_t time_us() const { return time_us_; }
  const Esdf& esdf() const { return filter_; }
  const CovarianceBounds& bounds() const { return bounds_; }
  const StateRecovery& recovery() const { return recovery_; }
  const NavFilterOptions& options() const { return options_; }
  const NavFilterCounters& counters() const { return counters_; }
  /// Per-sensor innovation records of the robot updates (not checkpointed).
  const SensorInnovationStats& innovations() const { return innovations_; }
  const std::vector<ImageRecord>& images() const { return images_; }
  const std::vector<LinkRecord>& links() const { return links_; }
  const std::vector<ProposalRecord>& proposals() const { return proposals_; }
  /// What navd publishes at time_us() (file comment "Published solution"); zero until initialised.
  Mat12 robot_covariance() const;
  Vec12 robot_mean() const;
  /// Pairs waiting for their registration, in proposal order (not checkpointed).
  std::vector<PendingRegistration> pending_registrations() const { return pending_.list(); }
  /// Sequence number of the newest deferred pair (0: none yet).
  std::uint64_t last_pending_sequence() const { return pending_.last_sequence(); }
  const PendingRegistrationCounters& pending_counters() const { return pending_.counters(); }
  /// Called at each image after its recovery, right before its link proposal (the time of use
  /// of the bounds: recovery/time_of_use.h); images().back() is that image. Not checkpointed.
  void set_before_proposal(std::function<void(const NavFilter&)> f) { before_proposal_ = f; }
  /// Image record of delayed-state block `block`, or nullptr (robot / unknown).
  const ImageRecord* image_of_state(int block) const;

  /// Everything the filter carries between measurements besides the ESDF, the bounds and the
  /// warm start (those have their own sections), in both directions: Archive is a WriteArchive
  /// or ReadArchive (core/serialization/archive.h); defined in nav_filter_serialization.h.
  /// Reading checks every index against the filter; a job in flight is stored awaited.
  template <class Archive>
  void serialize(Archive& ar);
  /// Replaces the ESDF, bounds and recovery (restored from their sections) as one step.
  void restore_map(Esdf filter, CovarianceBounds bounds, StateRecovery recovery);

 private:
  Status try_initialise(const Measurement& m);
  Status initialise(std::int64_t t_us);
  Status predict_once(double dt_s);
  std::optional<Vec12> conditional_robot_mean() const;
  void relinearise_robot();
  void update_robot(const Measurement& m);
  template <class Model>
  void fuse(const AidObservation<Model>& aid);
  Status on_image(const ImageEvent& image);
  bool recover();
  void extend_warm_start();
  bool certify(const RecoveryResult& result);
  void take_recovery_result(), submit_recovery_job();
  void propose_and_link(ImageRecord& current);
  LinkRecord try_link(const LinkHypothesis& h, const ImageRecord& current);
  /// Gates a registered pair (earlier block joint.state, later block `block_j`), applies it.
  void resolve_link(const LinkProposal& joint, int block_j, const RegistrationResult& reg,
                    LinkRecord& link);
  void finish_pending(PendingRegistrations::Entry& pending, const RegistrationResult* reg);
  void warn(const std::string& message) const;
  /// After reading a checkpoint: the block, image, link or sensor index it lacks ("": none).
  std::string index_error() const;

  NavFilterOptions options_;
  SensorModels sensors_;
  const RegistrationTable* registrations_;
  ConstantVelocityModel process_;
  Esdf filter_{12};
  StateRecovery recovery_;  ///< with an executor: 0 iterations (certification only)
  CovarianceBounds bounds_;
  BoundsSnapshot renewal_snapshot_;  ///< of the Λ of the lagged renewal in flight
  RecoverySchedule jobs_;
  LinkProposer proposer_;
  LinkGate gate_;
  AidGate aid_gate_;
  PendingRegistrations pending_;
  WarmStartTracker warm_;
  HeldInitialisation init_;
  bool initialised_ = false;
  std::int64_t time_us_ = 0;           ///< the robot's time
  std::int64_t last_validity_us_ = 0;  ///< newest measurement processed
  std::int64_t now_realtime_us_ = 0;   ///< host_realtime_us of the measurement in process()
  long pending_image_ = -1;  ///< image the next prediction keeps (index into images_), or -1
  std::vector<std::size_t> pending_links_;  ///< links_ rows waiting for state_j
  double altitude_m_;
  double last_relative_residual_ = 0.0;
  std::vector<long> image_of_block_;  ///< block -> images_ index (-1: robot / none)
  std::vector<ImageRecord> images_;
  std::vector<LinkRecord> links_;
  std::vector<ProposalRecord> proposals_;
  std::vector<LinkHypothesis> scratch_hypotheses_;
  NavFilterCounters counters_;
  SensorInnovationStats innovations_;
  std::function<void(const NavFilter&)> before_proposal_;
};

}  // namespace nav::core
