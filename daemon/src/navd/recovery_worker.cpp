#include "navd/recovery_worker.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <vector>

namespace nav::navd {
namespace {

core::StateRecoveryOptions fixed_iterations(int iterations) {
  core::StateRecoveryOptions options;
  options.mode = core::RecoveryMode::kFixedIterations;
  options.iterations_per_step = iterations;
  return options;
}

/// While no new snapshot is waiting, the newest one is solved again (each solve the configured
/// fixed number of PCG iterations, from the warm start) up to this many times or until the
/// worst column's relative residual is below kConvergedResidual: the filter never waits for
/// it, and the covariance column converges when the thread has spare time.
constexpr int kMaxIdleRefinements = 40;
constexpr double kConvergedResidual = 1e-8;
/// PCG iterations of an idle re-solve: a longer solve of the newest snapshot while the thread
/// has spare time, so the covariance column converges between filter steps.
constexpr int kIdleIterations = 50;

}  // namespace

RecoveryWorker::RecoveryWorker(const core::Vec12& x0, const core::Mat12& P0,
                               int iterations_per_step, RecoveryInbox& inbox,
                               RecoveryOutbox& outbox, SolutionBoard& board)
    : recovery_(12, fixed_iterations(iterations_per_step)),
      inbox_(inbox),
      outbox_(outbox),
      board_(board) {
  if (core::Status s = recovery_.initialize(x0, P0); !s.ok()) {
    spdlog::error("navd recovery: initialise: {}", s.to_string());
    broken_ = true;
  }
}

RecoveryCounters RecoveryWorker::run(const std::atomic<bool>& stop) {
  std::vector<PredictionRecord> records;
  FilterSnapshot snapshot;
  int refinements = 0;  // extra solves of the current snapshot while idle
  bool have_snapshot = false;
  while (!stop.load()) {
    const bool idle_refine = have_snapshot && refinements < kMaxIdleRefinements &&
                             counters_.last_relative_residual > kConvergedResidual;
    if (!inbox_.take(records, snapshot, idle_refine ? 0 : 50)) {
      if (idle_refine && !broken_) {
        ++refinements;
        ++counters_.idle_refinements;
        refine(snapshot);
      }
      continue;
    }
    have_snapshot = true;
    refinements = 0;
    if (broken_ || !extend(records)) continue;
    solve(snapshot);
  }
  return counters_;
}

bool RecoveryWorker::extend(const std::vector<PredictionRecord>& records) {
  for (const PredictionRecord& r : records) {
    core::Status s =
        recovery_.extend_for_prediction(r.F, r.Q, r.robot_mean, r.keep_current, r.kept_block);
    if (!s.ok()) {
      spdlog::error("navd recovery: warm start extension failed: {}", s.to_string());
      broken_ = true;
      return false;
    }
  }
  return true;
}

void RecoveryWorker::refine(const FilterSnapshot& snapshot) {
  const core::StateRecoveryOptions configured = recovery_.options();
  core::StateRecoveryOptions longer = configured;
  longer.iterations_per_step = std::max(configured.iterations_per_step, kIdleIterations);
  (void)recovery_.set_options(longer);
  solve(snapshot);
  (void)recovery_.set_options(configured);
}

void RecoveryWorker::solve(const FilterSnapshot& snapshot) {
  const auto start = std::chrono::steady_clock::now();
  const core::RecoveryResult result = recovery_.solve(snapshot.lambda, snapshot.eta);
  counters_.total_solve_s +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ++counters_.solves;
  counters_.last_relative_residual = result.max_relative_residual;
  counters_.last_mean_relative_residual = result.mean_relative_residual;
  RecoveredState state;
  state.step = snapshot.step;
  state.ok = result.status.ok();
  state.iterations = result.iterations;
  state.relative_residual = result.max_relative_residual;
  state.filter_robot_mean = snapshot.filter_robot_mean;
  if (!state.ok) {
    ++counters_.failures;
    spdlog::warn("navd recovery: step {}: {}", snapshot.step, result.status.to_string());
  } else {
    state.mean = recovery_.mean();
    state.robot_covariance = recovery_.robot_covariance();
  }
  const core::Mat12 covariance = state.robot_covariance;
  const bool ok = state.ok;
  outbox_.put(std::move(state));
  board_.modify([&](SolutionView& v) {
    if (ok) v.robot_covariance = covariance;
    v.cg_relative_residual = result.max_relative_residual;
    v.cg_iterations = result.iterations;
  });
}

}  // namespace nav::navd
