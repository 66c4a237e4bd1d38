#pragma once
// NavFilter's configuration as plain values (no file format): the sensors' mounts, noise and
// camera calibration, the process noise, the recovery and bound settings, the link proposal
// and gate, the recovery schedule and the asynchronous registrations. navd fills it from its
// YAML config (daemon/filter/filter_options.h); tests fill it directly.

#include <functional>
#include <string>
#include <vector>

#include "nav/core/models/constant_velocity.h"
#include "nav/core/navigation/aid_gate.h"
#include "nav/core/navigation/link_proposer.h"
#include "nav/core/navigation/recovery_executor.h"
#include "nav/core/navigation/sensor_models.h"
#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::core {

/// The default recovery options with the block-Jacobi preconditioner (NavFilter's default).
inline StateRecoveryOptions block_jacobi_recovery() {
  StateRecoveryOptions o;
  o.preconditioner = RecoveryPreconditioner::kBlockJacobi;
  return o;
}

struct NavFilterOptions {
  /// One entry per sensor, indexed by MeasurementTime::sensor_index.
  std::vector<SensorModelOptions> sensors;
  ConstantVelocityOptions process_noise;   ///< of the constant-velocity prediction
  bool propose_links = true;               ///< false: dead reckoning (no camera links)
  double initial_xy_sigma_m = 0.01;        ///< prior sigma of x, y (the world origin)
  double initial_velocity_sigma_mps = 0.5;  ///< prior sigma of u, v, w
  double initial_rate_sigma_radps = 0.05;  ///< prior sigma of p, q, r
  double max_predict_step_s = 0.5;         ///< longer gaps are predicted in steps, > 0
  /// A measurement less than this after the filter's time is applied at that time (no
  /// prediction), in [0, max_predict_step_s): the process noise of a millisecond prediction
  /// has a pose block ~dt³ whose inverse makes the information form lose its digits.
  double min_predict_step_s = 0.005;
  double default_altitude_m = 3.0;         ///< footprint altitude before any altitude, > 0
  /// Link hypotheses: probability, overlap fraction and per-image cap (link_proposer.h).
  LinkProposerOptions proposal;
  double camera_gate_chi2 = 15.086;        ///< 5-dof gate (chi2 99 %)
  /// Innovation gates of the DVL, attitude and depth updates and their reset (aid_gate.h).
  AidGateOptions aid_gate;
  /// PCG iterations per image; block Jacobi by default (the factor preconditioner refactors Λ
  /// at every image: opt-in, docs/performance.md).
  StateRecoveryOptions recovery = block_jacobi_recovery();
  BoundsOptions bounds;                    ///< certified (default)
  /// false: the PCG iterations run synchronously at each image (the reference path); true: as
  /// jobs of a RecoveryExecutor on a snapshot, taken at data times (recovery_executor.h).
  bool recovery_thread = false;
  /// Data time from an image's snapshot to the first measurement at which the filter takes the
  /// job's result (it waits there if the job is not done), s, [0, 3600].
  double recovery_handoff_s = 10.0;
  /// Makes the executor of the recovery jobs (recovery_thread only; navd: a thread). Empty:
  /// InlineRecoveryExecutor, which runs each job at its hand-off (bit-identical outputs).
  RecoveryExecutorFactory recovery_executor;
  /// Where the filter's renewals with recovery.renewal_lag > 0 run (lagged_renewal.h; navd: a
  /// thread). Empty: on the filter thread when taken (the same outputs).
  MarginalsLauncher renewal_launcher;
  /// How long after an image's receive time a proposed pair waits for its registration, s,
  /// [0, 3600]; 0: no waiting, the registration table is complete (pending_registrations.h).
  double registration_wait_s = 0.0;
  /// Bound on the pending pairs (storage reserved at construction), [1, 100000].
  int max_pending_registrations = 256;
  /// Receives a message for each rejected update, failed recovery or refused link (core has
  /// no logging; navd logs them). Empty: dropped. Counters record them either way.
  std::function<void(const std::string&)> warn;
};

/// The options, checked: std::invalid_argument naming the values otherwise.
NavFilterOptions validated(NavFilterOptions o);

}  // namespace nav::core
