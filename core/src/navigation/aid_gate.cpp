// Innovation gate of the robot updates (navigation/aid_gate.h).
#include "nav/core/navigation/aid_gate.h"

#include <cmath>
#include <optional>
#include <stdexcept>

#include "nav/core/navigation/chi_square.h"
#include "nav/core/navigation/innovation_stats.h"

namespace nav::core {
namespace {

double sigma_of(const AidGateOptions& o, AidKind kind) {
  switch (kind) {
    case AidKind::kDvl:
      return o.dvl_sigma;
    case AidKind::kRollPitch:
      return o.roll_pitch_sigma;
    case AidKind::kHeading:
      return o.heading_sigma;
    case AidKind::kDepth:
      return o.depth_sigma;
  }
  return 0.0;
}

}  // namespace

void validate(const AidGateOptions& o) {
  const char* names[kNumAidKinds] = {"dvl_sigma", "roll_pitch_sigma", "heading_sigma",
                                     "depth_sigma"};  // in AidKind order
  for (int k = 0; k < kNumAidKinds; ++k) {
    const double sigma = sigma_of(o, static_cast<AidKind>(k));
    if (!(sigma >= 0.0 && sigma <= 1000.0)) {
      throw std::invalid_argument(std::string("AidGateOptions: ") + names[k] + " = " +
                                  std::to_string(sigma) + " is not in [0, 1000]");
    }
  }
  if (!(o.reset_timeout_s >= 0.0 && o.reset_timeout_s <= 1e6)) {
    throw std::invalid_argument("AidGateOptions: reset_timeout_s = " +
                                std::to_string(o.reset_timeout_s) + " is not in [0, 1e6]");
  }
}

AidGate::AidGate(const AidGateOptions& options) : options_(options) {
  validate(options_);
  for (int k = 0; k < kNumAidKinds; ++k) {
    const double g = sigma_of(options_, static_cast<AidKind>(k));
    // Two-sided tail of a g-sigma scalar gate, carried to 1..4 dof (chi_square.h); a gate so
    // wide that the probability rounds to 1 stays g² per dof (never tighter than scalar).
    const double p = std::erf(g / std::sqrt(2.0));
    for (int dim = 1; dim <= 4; ++dim) {
      double gamma = 0.0;
      if (g > 0.0) gamma = p < 1.0 ? chi_square_quantile(p, dim) : g * g * dim;
      gate_chi2_[static_cast<std::size_t>(k)][static_cast<std::size_t>(dim - 1)] = gamma;
    }
  }
}

double AidGate::gate_sigma(AidKind kind) const { return sigma_of(options_, kind); }

double AidGate::chi2_gate(AidKind kind, int dim) const {
  if (dim < 1 || dim > 4) {
    throw std::invalid_argument("AidGate: measurement dimension " + std::to_string(dim) +
                                " is not in [1, 4]");
  }
  return gate_chi2_[static_cast<std::size_t>(kind)][static_cast<std::size_t>(dim - 1)];
}

AidGate::Run& AidGate::run_of(std::size_t sensor, AidKind kind) {
  const std::size_t i = sensor * kNumAidKinds + static_cast<std::size_t>(kind);
  if (i >= runs_.size()) runs_.resize(i + 1);
  return runs_[i];
}

AidGateDecision AidGate::decide(std::size_t sensor, AidKind kind, std::int64_t t_us,
                                const MeasVec& nu, const MeasJac& H, const MeasCov& R,
                                const Mat12& P, double nis) {
  AidGateDecision d;
  d.gate_sigma = gate_sigma(kind);
  const double gamma = chi2_gate(kind, static_cast<int>(nu.size()));
  if (gamma <= 0.0 || nis < 0.0) return d;  // off, or S not positive definite
  Run& run = run_of(sensor, kind);
  d.test_ratio = nis / gamma;
  if (run.start_us < 0) {
    if (d.test_ratio <= 1.0) return d;
    run.start_us = t_us;  // a run opens: the gate keeps this P
    run.P = P;
    run.resetting = false;
    d.fuse = false;
    d.run_started = true;
    return d;
  }
  if (run.resetting) {
    // start_us: the last update that failed the gate on the current S. The run closes once
    // every update has passed for kResetSettleS (the estimate came to the sensor, its rates too).
    if (d.test_ratio > 1.0) run.start_us = t_us;
    if (t_us - run.start_us >= static_cast<std::int64_t>(kResetSettleS * 1e6)) {
      run.start_us = -1;
      run.resetting = false;
      return d;
    }
    d.reset = true;
    return d;
  }
  // In a run: against the covariance it opened with (the file comment).
  const std::optional<double> run_nis = nis_of(nu, MeasCov(H * run.P * H.transpose() + R));
  const double run_ratio = run_nis ? *run_nis / gamma : -1.0;
  if (run_ratio >= 0.0 && run_ratio <= 1.0) {
    run.start_us = -1;
    d.test_ratio = run_ratio;
    return d;
  }
  d.test_ratio = run_ratio >= 0.0 ? run_ratio : d.test_ratio;
  const auto timeout_us = static_cast<std::int64_t>(std::llround(options_.reset_timeout_s * 1e6));
  if (t_us - run.start_us >= timeout_us) {
    run.resetting = true;  // EKF2's reset after a timeout: fuse until the gate passes
    run.start_us = t_us;
    d.reset = true;
    d.reset_started = true;
    return d;
  }
  d.fuse = false;
  return d;
}

}  // namespace nav::core
