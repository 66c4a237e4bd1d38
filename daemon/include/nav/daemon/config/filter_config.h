#pragma once
// The `filter:` section of the navd config (config/README.md "filter"), mapped onto
// core::NavFilterOptions by filter/filter_options.h.

#include "nav/core/models/constant_velocity.h"
#include "nav/core/navigation/aid_gate.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::daemon {

struct FilterConfig {
  core::ConstantVelocityOptions process_noise;  ///< process_noise_psd.{accel, angular_accel}
  int cg_iterations_per_step = 5;               ///< [1, 1000]
  double latency_window_ms = 200.0;             ///< [0, 60000]
  double gating_chi2_threshold = 16.81;         ///< [1e-6, 1e6]; 16.81 = chi2(6 dof, 99 %)
  /// Innovation gates of the DVL, roll/pitch, heading and depth updates in sigmas ([0, 1000],
  /// 0: off) and the reset after a run of rejections, s ([0, 1e6]): *_gate_sigma and
  /// aid_gate_reset_s (nav/core/navigation/aid_gate.h).
  core::AidGateOptions aid_gate;
  /// PCG iterations on the recovery thread (true) or synchronously at each image (false, the
  /// default: the thread made the default dive's replay ~15 % slower, README "Recovery thread").
  bool recovery_thread = false;
  /// The PCG preconditioner (block_jacobi | factor | kept_factor: a Cholesky factor of Λ refactored every
  /// recovery_refresh_interval images, core/recovery/factor_preconditioner.h).
  core::RecoveryPreconditioner recovery_preconditioner = core::RecoveryPreconditioner::kBlockJacobi;
  /// kept_factor: the factor is kept equal to Λ by row modifications and rank updates at every
  /// image and the refresh only renews the exact marginals (core/recovery/kept_equal_factor.h).
  bool recovery_keep_factor_equal = false;
  int recovery_refresh_interval = 1;  ///< [1, 100000]
  /// kept_factor: the newest states ordered last at each refactorisation, [0, 100000]
  /// (core/recovery/kept_equal_factor.h; 0: plain AMD).
  int recovery_kept_recent_states = core::StateRecoveryOptions{}.kept_factor_recent_blocks;
  /// kept_factor: images from the snapshot of a renewal of the exact marginals to its use, the
  /// renewal computed on a thread meanwhile; [0, recovery_refresh_interval), 0: at its image
  /// (core/recovery/lagged_renewal.h).
  int recovery_renewal_lag = 0;
  /// factor / kept_factor: refactor (renew) also when the map has grown by this fraction since
  /// the last time, [0, 1e6]; 0: every recovery_refresh_interval images only.
  double recovery_refresh_growth = 0.0;
  /// factor: refactor also after a solve that left a relative residual above this, [1e-12, 1e12]
  double recovery_refresh_residual = 1e-6;
  /// Data time from an image to the measurement at which the filter takes the recovery
  /// thread's result, s, [0, 3600] (nav/core/navigation/recovery_executor.h; the next image takes
  /// it earlier: 10 s is past sim.yaml's 8 s image period, so replays overlap a whole period).
  double recovery_handoff_s = 10.0;
  /// How long a proposed pair waits for an asynchronous registration after its image's
  /// receive time, s, [0, 3600] (nav/core/navigation/pending_registrations.h); 0: the
  /// registration table is complete when the image is processed (replay of a dive log).
  /// The live mode needs > 0 (its vision stage answers after the image).
  double registration_wait_s = 0.0;
  int max_pending_registrations = 256;  ///< bound on the waiting pairs, [1, 100000]
  /// Link hypotheses (nav/core/navigation/link_proposer.h): a pair is proposed when the
  /// probability that the footprints overlap by >= proposal_min_overlap reaches
  /// proposal_min_probability, the most probable proposal_max_per_image per image.
  double proposal_min_probability = 0.05;  ///< [1e-9, 1 - 1e-9]
  double proposal_min_overlap = 0.2;       ///< [1e-3, 1]
  int proposal_max_per_image = 15;         ///< [1, 100000]
};

}  // namespace nav::daemon
