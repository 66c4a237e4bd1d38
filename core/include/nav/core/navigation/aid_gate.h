#pragma once
// Chi-square innovation gate of NavFilter's robot updates (aid_sources.h), per sensor and kind
// (DVL velocity, roll/pitch, heading, depth), as PX4 EKF2 gates each aid source
// (src/modules/ekf2/EKF/aid_sources: test ratio against EKFx_*_GATE in standard deviations,
// reset after a timeout) and as Bar-Shalom, Li & Kirubarajan (2001, §5.4, §7.4) validate a
// measurement by its normalised innovation squared.
//
// Gate: the update's NIS = νᵀ S⁻¹ ν (innovation_stats.h, S = H P Hᵀ + R with P the robot
// covariance NavFilter tracks) against the chi-square gate of dim z at the tail probability
// of a g-sigma scalar gate: γ = chi²_dim⁻¹(P(|N(0,1)| <= g)) (g = 5: γ = 25, 28.7, 31.8 for
// 1, 2, 3 dof). Test ratio = NIS / γ; > 1 rejects (nothing is applied: the information matrix,
// vector, mean, bound and tracked P stay bit-identical). g = 0 turns the kind's gate off.
//
// Runs of rejections. A sensor that goes bad (stuck, garbage) is refused, the filter
// dead-reckons and P grows with the process noise: compared against that growing S a stuck
// heading would pass after a few seconds (sim.yaml's yaw PSD gives a 26-degree heading sigma
// after 10 s without heading) and pull the estimate onto the stuck value. So while a run is
// open (from its first rejection) an update is tested against S_run = H P_run Hᵀ + R, with P_run
// the tracked P at the run's first rejection: an isolated outlier ends the run at the next good
// measurement (its innovation fits the P it had before); garbage or a stuck sensor stays out.
// Reset after timeout (EKF2's reset on a timed-out aid source): once the run has lasted
// reset_timeout_s of data time the kind is fused again, every update, until all have passed
// the gate against the current S for kResetSettleS (the estimate has come to the sensor, and
// the rates learnt while dead-reckoning have converged: closing at the first pass opened a new
// run on the post-reset covariance at once, docs/faults.md) and the run closes. The
// trade-off: a real step of the sensor (a heading jump, a DVL whose velocity the estimate lost
// beyond P_run) is refused for reset_timeout_s while the filter dead-reckons; a fault longer
// than reset_timeout_s is fused after it. The default, 60 s, outlasts the fault campaign's
// faults (10-30 s, docs/faults.md); a DVL back after an outage is not a run (nothing was
// rejected: its first update is gated against the P grown during the outage).
//
// Runs are not checkpointed (a restored filter starts without one, as its innovation stats).

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/core/models/measurement.h"

namespace nav::core {

enum class AidKind { kDvl = 0, kRollPitch = 1, kHeading = 2, kDepth = 3 };
inline constexpr int kNumAidKinds = 4;
inline constexpr double kResetSettleS = 2.0;  ///< passes a reset needs to close its run, s

struct AidGateOptions {
  /// Gates in standard deviations of a scalar innovation, each in [0, 1000]; 0: off.
  double dvl_sigma = 5.0;
  double roll_pitch_sigma = 5.0;
  double heading_sigma = 5.0;
  double depth_sigma = 5.0;
  /// Data time of a run of rejections after which the kind is fused again, s, [0, 1e6].
  double reset_timeout_s = 60.0;
};

/// Throws std::invalid_argument naming the first option out of range.
void validate(const AidGateOptions& o);

/// What the gate decided for one update.
struct AidGateDecision {
  bool fuse = true;
  double test_ratio = 0.0;  ///< NIS / γ against the S used (0 when the gate is off or S invalid)
  double gate_sigma = 0.0;  ///< the kind's g
  bool run_started = false;  ///< the first rejection of a run
  bool reset = false;        ///< fused by the timeout reset
  bool reset_started = false;  ///< the first update fused by a run's reset
};

class AidGate {
 public:
  explicit AidGate(const AidGateOptions& options);

  /// The chi-square gate γ of `kind` for a `dim`-dimensional measurement (0: off).
  double chi2_gate(AidKind kind, int dim) const;
  double gate_sigma(AidKind kind) const;

  /// Decides one update of (sensor, kind) at t_us: ν the innovation, H its Jacobian, R its
  /// noise, P the tracked robot covariance, nis = νᵀ (H P Hᵀ + R)⁻¹ ν (< 0: S not positive
  /// definite, fused ungated: the ESDF refuses what it cannot apply).
  AidGateDecision decide(std::size_t sensor, AidKind kind, std::int64_t t_us, const MeasVec& nu,
                         const MeasJac& H, const MeasCov& R, const Mat12& P, double nis);

 private:
  struct Run {
    std::int64_t start_us = -1;  ///< first rejection (-1: no run); resetting: last failure
    bool resetting = false;
    Mat12 P = Mat12::Zero();     ///< tracked P at the first rejection
  };
  Run& run_of(std::size_t sensor, AidKind kind);

  AidGateOptions options_;
  std::array<std::array<double, 4>, kNumAidKinds> gate_chi2_{};  ///< [kind][dim - 1]
  std::vector<Run> runs_;  ///< sensor * kNumAidKinds + kind
};

}  // namespace nav::core
