#pragma once
// NavFilter: the view-based SLAM filter on measurements (Eustice et al., "Visually Navigating
// the RMS Titanic with SLAM Information Filters", RSS 2005), shared by navd and `navtool
// replay`. Owns the ESDF (core::Esdf, 12-element blocks), the state recovery (fixed-iteration
// PCG, core::StateRecovery) and the Algorithm 1 bounds (core::CovarianceBounds).
//
// Measurements must arrive in time-of-validity order (TimeOrderingBuffer's job); one older than
// the newest processed is counted (`out_of_order`) and skipped.
// * Initialisation (hil-tests/README.md "World frame"): measurements are held until a
//   roll/pitch, a heading and a depth have been seen; then the filter starts at the FIRST held
//   measurement's time (the start of the dive, the world origin) with x = y = 0 (sigma
//   initial_xy_sigma_m), z from the depth minus the sensor's lever arm, attitude from the
//   attitude sensor (priors 10x the sensor sigmas), velocities and rates 0 with loose priors,
//   and every held measurement is processed. More than 1024 held measurements are dropped and
//   counted (`before_initialisation`).
// * Predict: constant-velocity model (filter.process_noise_psd) to each measurement's time, in
//   steps of at most max_predict_step_s. A measurement less than min_predict_step_s (5 ms) after
//   the filter's time is applied at the filter's time instead: the process noise of a
//   millisecond prediction has a pose block ~dt³ (1e-14 for a 2 ms step), whose inverse makes
//   the information form lose every digit at depths of kilometres (measured: a 6 m jump of the
//   estimate at 3,800 m). Sensors sampled together (HDT, PHTRO, within the 2 ms jitter) share
//   one prediction; the time error is below the grouping gap. The gap must stay well below the
//   sensor periods: at 50 ms, headings and images were applied at the time of another sample up
//   to 50 ms earlier (the DVL's, dated by its clock mapping, most likely), which lagged the
//   heading 18-23 ms in the 10 deg/s turns (0.2 deg at 0.025 deg sigma): heading NEES 6.5 on the
//   default dive, 0.87 with 5 ms (hil-tests/README.md "Consistency"). Updates: DVL, roll/pitch, heading, depth with the
//   config mounts and noise (sensor_models.h). Altitude sets the camera footprint size (no
//   seabed model); angular rates are counted and not used.
// * Every robot update is applied to the robot bound as well (a Kalman update of B_rr, still an
//   upper bound of Σ_rr), so the bound stored for each new delayed state stays tight.
// * Before each prediction the robot is relinearised in O(1): μ_r = Λ_rr⁻¹(η_r − Σ_j Λ_rj μ_j)
//   over its few neighbours (its conditional mean given the delayed states).
// * ImageEvent at t: predict to t; recover (the warm start is extended once across
//   everything since the last recovery: the robot's own predictions and updates compose into
//   Σ'_ir = Σ_ir Aᵀ and a 12 x 12 Kalman filter of Σ_rr, which is exact for an exact previous
//   recovery except for the link updates; O(1) per measurement, O(map) once per image), then `recovery.iterations_per_step` PCG
//   iterations on the current Λ, η; the delayed states take the recovered mean); hand the
//   recovery to the bounds (certified, bounds.h); then, if links are enabled, propose links
//   from the robot (= this image) to every earlier delayed state i (test below), look each
//   proposed pair up in the RegistrationTable and gate it; accepted links update the ESDF
//   (CameraRelativePoseModel with the camera mount, robot <-> i) and tighten Σ~_ii (bounds
//   update, constant time). The robot is kept as this image's delayed state by the next
//   prediction (Esdf::predict keep_current), with its links; finish() keeps a pending one.
// * Asynchronous registrations (options.registration_wait_s > 0, filter.registration_wait_s;
//   nav_filter_pending.cpp): the vision stage answers a proposed pair later than the image. A
//   pair whose registration is not in the table with available_us (its utime, host
//   CLOCK_REALTIME) <= the current measurement's host_realtime_us is kept pending (at most
//   max_pending_registrations; more are not_registered at once, counted) with its proposal
//   joint. Before every later measurement (after its prediction) each pending pair whose
//   registration is now available (available_us <= that measurement's host_realtime_us) is
//   gated and applied as a link between the two delayed states (Esdf binary update; the gate
//   uses the stored proposal joint, an upper bound of the current joint since information
//   only grows); one not answered within registration_wait_s of its image's receive time is
//   not_registered. Its links.csv row is appended then (t_us = the filter's time). Deferred
//   links do not tighten Σ~_ii (the stored joint's robot part is no longer the robot's bound;
//   an untightened bound stays conservative). Because availability is judged by the
//   registrations' utime against the measurements' receive times, a table filled before the
//   replay and one filled while it runs (live mode) give the same links when every
//   registration is inserted before the first measurement received at or after its utime.
//   Pending pairs are not checkpointed (a resumed filter forgets them); finish() expires them.
//   registration_wait_s = 0 (default): the table is complete (a dive log's oracle
//   registrations): looked up at the image regardless of available_us, as before.
// * Recovery thread (options.recovery_thread, filter.recovery_thread; opt-in, measured in README
//   "Recovery thread"):
//   the PCG iterations move to a RecoveryWorker (recovery_worker.h). At image k the filter
//   takes the job in flight if any, extends the warm start as above, evaluates its TRUE residual
//   on the current Λ (a 0-iteration solve: the certificate the bounds need, so the bounds stay
//   certified whatever the lag) and proposes/applies links exactly as above from it; then it
//   copies Λ, η (after the links) and the warm start into the worker's buffers and the thread
//   runs the iterations. The filter takes the result at the first measurement with time of
//   validity >= t_k + recovery_handoff_s, at the next image or at finish() (whichever comes
//   first; it waits if the thread is not done): the warm start becomes the result (the
//   predictions and updates since stay in A and P, P moved by A (Σ'_tt − Σ_tt) Aᵀ), and the
//   delayed states of the snapshot take its mean (their relinearisation point). Hand-off points
//   are DATA times, so the outputs are bit-identical whatever the thread timing (and equal to
//   options.recovery_inline, which runs each job on the filter thread at its hand-off). The
//   image's relative_residual and max_cg_relative_residual are then those of the certificate
//   (the extended result of the previous job on the current Λ), the residual the bounds use.
//   The filter-thread cost per image drops from the PCG iterations (one Λ product each) to the
//   residual product and the snapshot copy; the job skips its own final residual product
//   (StateRecoveryOptions::recompute_true_residual = false: the certificate above replaces it).
//   Hand-off choice: replaying the default dive, the job (5 iterations) costs more CPU than the
//   filter's own work between two images (perf: 9.8 s vs ~6 s over the dive), so a hand-off
//   1 s after the image overlaps only ~1/8 of that work and the filter waits for nearly the
//   whole job; the default 10 s (the next image, 8 s later, takes it first) overlaps it all.
//   Measured on the 2-core machine (README): the replay still got ~15 % slower than with
//   synchronous recovery (the Λ copy and the certificate product add CPU, and the job competes
//   with the dead-reckoning twin's thread), so the thread is opt-in.
//   Between images nothing reads the delayed states the job refines except checkpoints and
//   published bounds (after the first prediction past the image the robot's only neighbour is
//   the newly kept state, not in the job's snapshot), so a later hand-off mostly delays when
//   they show the refined mean. Checkpoints store an awaited job
//   (nav_filter_checkpoint.h). Copying a NavFilter gives the copy its own worker (and the job's
//   result, waited for); destroying it waits for a job in flight.
// * Proposal test: with Δ = p_i − p_r (world x, y) and its covariance C from the certified
//   proposal joint [Σ_rr Σ_ri; Σ_ir Σ~_ii], the pair is proposed when the confidence ellipse
//   Δᵀ C⁻¹ Δ <= chi2(2 dof, proposal_confidence) can reach within D of the origin, tested as
//     ‖Δ‖ − sqrt(chi2 · λmax(C)) < D,   D = r_i + r_j + 2 ‖lever_xy‖,
//   r = altitude · footprint half-diagonal per metre (the images' footprints can touch).
// * Gate: d² = νᵀ (H J Hᵀ + R)⁻¹ ν with ν = z − h(μ_i, μ_r) (angles wrapped), H = [H_r H_i]
//   and J = [Σ^_rr Σ^_ri; Σ^_ir Σ~_ii]: the proposal joint WITHOUT the truncation inflation
//   ε I of bounds.h (that isotropic term, in m² and rad² alike, is tens of degrees on the
//   rotation rows after a few PCG iterations and would let any outlier through; proposal keeps
//   it so that no pair is missed). Accepted when d² <= camera_gate_chi2 (5 dof; derived from the
//   config's 6-dof filter.gating_chi2_threshold at the same probability, chi_square.h).
// * Link update: an accepted link is linearised at the iterated-EKF point of the robot (state i
//   held at its mean; Gauss-Newton on the link and the robot's recovered Σ_rr, <= 10 steps,
//   nav_filter_links.cpp), not at the possibly stale mean: after a camera-off transit with a
//   DVL dropout the mean can be metres off on a baseline of a few metres, and a bearing link
//   linearised there moves the map to the wrong place (hil-tests/README.md "Consistency").
//
// Work per measurement is O(1) in the map size; per image O(map) (recovery, one proposal test
// per delayed state), as in the paper. Not thread-safe (one owner thread; the recovery thread
// touches only its own snapshot).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "nav/core/filter/esdf.h"
#include "nav/core/models/constant_velocity.h"
#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/state_recovery.h"
#include "nav/core/status.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/innovation_stats.h"
#include "nav/daemon/filter/recovery_worker.h"
#include "nav/daemon/filter/sensor_models.h"
#include "nav/daemon/measurement.h"
#include "nav/daemon/registration_table.h"

namespace nav::daemon {

struct NavFilterOptions {
  bool propose_links = true;               ///< false: dead reckoning (no camera links)
  double initial_xy_sigma_m = 0.01;        ///< prior sigma of x, y (the world origin)
  double initial_velocity_sigma_mps = 0.5;  ///< prior sigma of u, v, w
  double initial_rate_sigma_radps = 0.05;  ///< prior sigma of p, q, r
  double max_predict_step_s = 0.5;         ///< longer gaps are predicted in steps, > 0
  /// A measurement less than this after the filter's time is applied at that time (no
  /// prediction); in [0, max_predict_step_s). See the file comment.
  double min_predict_step_s = 0.005;
  double default_altitude_m = 3.0;         ///< footprint altitude before any altitude, > 0
  double proposal_confidence = 0.99;       ///< of the proposal ellipse, in (0, 1)
  double camera_gate_chi2 = 15.086;        ///< 5-dof gate (from_config derives it)
  core::StateRecoveryOptions recovery;     ///< fixed iterations (from_config)
  core::BoundsOptions bounds;              ///< certified (default)
  /// false: the PCG iterations run synchronously at each image (the reference path); true: on
  /// the recovery thread (file comment "Recovery thread"; from_config: filter.recovery_thread).
  bool recovery_thread = false;
  /// Data time from an image's snapshot to the first measurement at which the filter takes the
  /// thread's result (it waits there if the job is not done), s, >= 0.
  double recovery_handoff_s = 10.0;
  /// With recovery_thread: run each job on the filter thread at its hand-off instead of on a
  /// thread (bit-identical outputs, for checking the thread).
  bool recovery_inline = false;
  /// Asynchronous registrations (file comment): how long after an image's receive time a
  /// proposed pair waits for its registration, s, [0, 3600]; 0: no waiting (complete table).
  double registration_wait_s = 0.0;
  /// Bound on the pending pairs (storage reserved at construction), [1, 100000].
  int max_pending_registrations = 256;
  /// Tests: runs on the recovery thread before each job (e.g. sleeps).
  std::function<void()> recovery_test_hook;

  /// Options for `config`: recovery.iterations_per_step = filter.cg_iterations_per_step,
  /// camera_gate_chi2 = the 5-dof equivalent of filter.gating_chi2_threshold,
  /// recovery_thread / recovery_handoff_s = filter.recovery_thread / recovery_handoff_s.
  static NavFilterOptions from_config(const NavdConfig& config);
};

enum class LinkOutcome { kAccepted, kGated, kRegistrationFailed, kNotRegistered };
const char* to_string(LinkOutcome outcome);

struct LinkRecord {  ///< one proposed pair (links.csv)
  std::int64_t t_us = 0;
  std::uint64_t frame_i = 0, frame_j = 0;  ///< earlier, later (the current image)
  int state_i = -1, state_j = -1;          ///< filter blocks (state_j once kept, else -1)
  LinkOutcome outcome = LinkOutcome::kNotRegistered;
  double mahalanobis_sq = -1.0;  ///< gate statistic (-1 when not registered / failed)
  bool is_outlier = false;       ///< registration's simulator truth
  /// The registration's measurement and covariance and the innovation z − h (when registered
  /// successfully; zero otherwise), for camera_link_t.
  Eigen::Matrix<double, 5, 1> z = Eigen::Matrix<double, 5, 1>::Zero();
  Eigen::Matrix<double, 5, 5> covariance = Eigen::Matrix<double, 5, 5>::Zero();
  Eigen::Matrix<double, 5, 1> innovation = Eigen::Matrix<double, 5, 1>::Zero();
};

/// A proposed pair waiting for its registration (file comment "Asynchronous registrations").
struct PendingRegistration {
  std::uint64_t sequence = 0;              ///< 1, 2, ... in proposal order
  std::uint64_t frame_i = 0, frame_j = 0;  ///< earlier, later image
  std::int64_t t_i_us = 0, t_j_us = 0;     ///< their times of validity
  std::int64_t asked_realtime_us = 0;      ///< image j's host_realtime_us
  std::int64_t deadline_realtime_us = 0;   ///< asked + registration_wait_s
};

struct PendingRegistrationCounters {
  std::uint64_t deferred = 0;      ///< pairs that waited for their registration
  std::uint64_t applied = 0;       ///< registration arrived in time (gated, maybe accepted)
  std::uint64_t accepted = 0;      ///< of applied: accepted links
  std::uint64_t expired = 0;       ///< no registration within the wait (or at finish())
  std::uint64_t dropped_full = 0;  ///< not deferred: max_pending_registrations reached
};

struct ProposalRecord {  ///< one image (proposals.csv)
  std::uint64_t frame_id = 0;
  int candidates = 0, proposed = 0, accepted = 0;
};

struct ImageRecord {  ///< the estimate at one image (trajectory.csv)
  std::int64_t t_us = 0;
  std::uint64_t frame_id = 0;
  int state = -1;                ///< its delayed-state block once kept
  double altitude_m = 0.0;       ///< used for its footprint
  core::Vec12 robot_mean = core::Vec12::Zero();            ///< after this image's links
  core::Mat12 robot_covariance = core::Mat12::Zero();      ///< recovered Σ_rr (before links)
  double relative_residual = 0.0;  ///< recovery's max relative residual
  /// Pose part of its bound when inserted (Σ~_ii = Σ_rr, Algorithm 1), once kept.
  Eigen::Matrix<double, 6, 6> initial_bound = Eigen::Matrix<double, 6, 6>::Zero();
};

struct NavFilterCounters {
  std::uint64_t measurements = 0, before_initialisation = 0, out_of_order = 0;
  std::uint64_t updates = 0, update_failures = 0, unused = 0;
  std::uint64_t predictions = 0, images = 0, duplicate_images = 0;
  std::uint64_t recoveries = 0, recovery_failures = 0;
  std::uint64_t candidates = 0, links_proposed = 0, links_accepted = 0, links_gated = 0;
  std::uint64_t registration_failed = 0, not_registered = 0;
  std::uint64_t outliers_rejected = 0, outliers_accepted = 0, bound_update_failures = 0;
  double max_cg_relative_residual = 0.0;
};

class NavFilter {
 public:
  /// `registrations` may be null (then every proposal is not_registered); it must outlive the
  /// filter. Throws std::invalid_argument for invalid options or camera calibration.
  NavFilter(const NavdConfig& config, const RegistrationTable* registrations,
            NavFilterOptions options);

  /// Processes one measurement (time-ordered). Returns an error only when the filter itself
  /// fails (prediction or recovery breakdown); a rejected measurement is counted instead.
  core::Status process(const Measurement& m);
  /// End of data: keeps a pending image as a delayed state (a short prediction).
  core::Status finish();
  /// One recovery step now (as at an image, without link proposal), e.g. before a final
  /// analysis; false if it failed (counted). With the recovery thread: takes the job in
  /// flight, then runs one job on the current Λ and waits for it.
  bool recover_now();
  /// A recovery-thread job is in flight (submitted, not yet taken).
  bool recovery_in_flight() const { return worker_.worker && worker_.worker->busy(); }

  bool initialised() const { return initialised_; }
  std::int64_t time_us() const { return time_us_; }
  const core::Esdf& esdf() const { return filter_; }
  const core::CovarianceBounds& bounds() const { return bounds_; }
  const core::StateRecovery& recovery() const { return recovery_; }
  const NavFilterOptions& options() const { return options_; }
  const NavFilterCounters& counters() const { return counters_; }
  /// Per-sensor innovation records of the robot updates (innovation_stats.h; not checkpointed).
  const SensorInnovationStats& innovations() const { return innovations_; }
  const std::vector<ImageRecord>& images() const { return images_; }
  const std::vector<LinkRecord>& links() const { return links_; }
  const std::vector<ProposalRecord>& proposals() const { return proposals_; }
  /// Pairs waiting for their registration, in proposal order (not checkpointed).
  std::vector<PendingRegistration> pending_registrations() const;
  /// Sequence number of the newest deferred pair (0: none yet).
  std::uint64_t last_pending_sequence() const { return pending_sequence_; }
  const PendingRegistrationCounters& pending_counters() const { return pending_counters_; }
  /// Image record of delayed-state block `block`, or nullptr (robot / unknown).
  const ImageRecord* image_of_state(int block) const;

 private:
  friend struct NavFilterCheckpointAccess;  // checkpoints: nav_filter_checkpoint.cpp
  struct Proposal {
    core::LinkProposal joint;
    std::size_t image = 0;  ///< index into images_
  };
  core::Status try_initialise(const Measurement& m);
  core::Status initialise(std::int64_t t_us);
  core::Status advance_to(std::int64_t t_us);
  core::Status predict_once(double dt_s);
  void relinearise_robot();
  void update_robot(const Measurement& m);
  /// ESDF update of the robot and the same Kalman update of the robot bound
  /// (CovarianceBounds::update_robot), counted.
  void track_robot_update(const core::MeasJac& H, const core::MeasCov& R);
  template <class Model>
  void update_unary(const Model& model, const core::MeasVec& z, const core::MeasCov& R,
                    const char* what, std::size_t sensor);
  core::Status on_image(const ImageEvent& image);
  bool recover();
  /// The warm start across everything since the last recovery (file comment "ImageEvent").
  void extend_warm_start();
  /// Hands recovery_'s solution (one solve on the current Λ, η) to the bounds and counters.
  bool certify(const core::RecoveryResult& result);
  // Recovery thread (nav_filter_recovery.cpp).
  void submit_recovery_job();
  void take_recovery_result();
  void propose_and_link(ImageRecord& current);
  bool is_candidate(const ImageRecord& earlier, const ImageRecord& current, int block,
                    core::LinkProposal* joint) const;
  LinkRecord try_link(const Proposal& p, const ImageRecord& current);
  /// Gates a registered pair (earlier block p.state, later block `block_j`) and applies it.
  void resolve_link(const core::LinkProposal& joint, int block_j, const RegistrationResult& reg,
                    LinkRecord& link);
  // Asynchronous registrations (nav_filter_pending.cpp).
  struct Pending {
    PendingRegistration info;
    core::LinkProposal joint;
    std::size_t image_j = 0;   ///< index into images_
    std::size_t proposal = 0;  ///< index into proposals_
  };
  /// True when the pair is kept waiting for its registration (not looked up now).
  bool defer_link(const Proposal& p, const ImageRecord& current);
  /// Applies the pending pairs whose registration is available at `realtime_us`, expires the
  /// overdue ones.
  void resolve_pending(std::int64_t realtime_us);
  void finish_pending(Pending& pending, const RegistrationResult* reg);
  double footprint_radius_m(double altitude_m) const;

  NavFilterOptions options_;
  SensorModels sensors_;
  const RegistrationTable* registrations_;
  core::ConstantVelocityModel process_;
  core::Esdf filter_{12};
  core::StateRecovery recovery_;  ///< with the thread: 0 iterations (certification only)
  core::CovarianceBounds bounds_;
  RecoveryWorkerSlot worker_;       ///< the recovery thread (recovery_thread only)
  std::int64_t handoff_us_ = 0;     ///< data time at which the job in flight is taken
  bool initialised_ = false;
  std::int64_t time_us_ = 0;           ///< the robot's time
  std::int64_t last_validity_us_ = 0;  ///< newest measurement processed
  // Seen before initialisation.
  std::optional<BodyAttitude> init_roll_pitch_, init_heading_;
  std::optional<Depth> init_depth_;
  std::size_t init_rp_sensor_ = 0, init_heading_sensor_ = 0;
  static constexpr std::size_t kMaxPreInit = 1024;
  std::vector<Measurement> pre_init_;  ///< held until initialisation, then replayed
  std::int64_t first_time_us_ = 0;
  // Since the last recovery (warm-start extension, see recover()): the linear map A with
  // Σ'_ir = Σ_ir Aᵀ (predictions F and robot updates I − K H composed) and the robot covariance
  // P tracked by a 12 x 12 Kalman filter from the recovered Σ_tt.
  core::Mat12 A_since_recovery_ = core::Mat12::Identity();
  core::Mat12 P_robot_ = core::Mat12::Zero();
  core::Mat12 sigma_tt_ = core::Mat12::Zero();
  bool predicted_since_recovery_ = false;
  int kept_since_recovery_ = -1;
  // The image whose delayed state the next prediction keeps (index into images_), or -1.
  long pending_image_ = -1;
  std::vector<std::size_t> pending_links_;  ///< links_ rows waiting for state_j
  double altitude_m_;
  double last_relative_residual_ = 0.0;
  double proposal_chi2_;
  std::vector<long> image_of_block_;  ///< block -> images_ index (-1: robot / none)
  std::vector<ImageRecord> images_;
  std::vector<LinkRecord> links_;
  std::vector<ProposalRecord> proposals_;
  std::vector<Proposal> scratch_proposals_;
  std::int64_t now_realtime_us_ = 0;  ///< host_realtime_us of the measurement in process()
  std::vector<Pending> pending_;      ///< capacity max_pending_registrations
  std::uint64_t pending_sequence_ = 0;
  std::uint64_t pending_seen_generation_ = 0;  ///< registrations_->generation() at last scan
  std::int64_t pending_next_check_us_ = 0;     ///< earliest availability / deadline pending
  PendingRegistrationCounters pending_counters_;
  NavFilterCounters counters_;
  SensorInnovationStats innovations_;
};

}  // namespace nav::daemon
