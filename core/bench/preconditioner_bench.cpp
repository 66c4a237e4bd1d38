// The recovery's two preconditioners (state_recovery.h) side by side at 1k, 10k and 100k
// states: how many PCG iterations one recovery step needs to reach a relative residual of
// 1e-6 in every column of [μ | Σ_{*r}], and what the step costs.
//
// Problem: the lawnmower survey graph (lawnmower_graph.h: odometry plus camera-overlap links
// across tracks). Each timed step first adds, untimed, a camera link between the newest state
// and a pseudo-random earlier one (the information a loop closure adds), then solves in
// kTolerance mode (1e-6, cap 3000 iterations) warm-started from the previous step's solution,
// as the recovery thread does. BM_RecoveryToTolerance/<preconditioner>/<states>:
//   * block_jacobi: blkdiag(Λ_ii), packed kernel (the navd default);
//   * factor: a CHOLMOD factor of Λ refreshed every 10 solves (refresh_interval 10, and when a
//     step ends above 1e-6), so the mean time includes a tenth of a refresh;
//   * kept_factor: the same refresh of the exact marginals every 10 solves, and a factor kept
//     equal to Λ by row modifications and rank updates as the preconditioner
//     (kept_equal_factor.h), so that one iteration is the direct solve.
// BM_FactorRefresh/<states>: one refresh alone (supernodal Cholesky plus the selected inversion
// that gives the exact marginals). Counters: iterations and refreshes per step, hit_cap (the
// fraction of steps stopped by the cap), dim. Results: docs/consistency.md.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <string>

#include "lawnmower_graph.h"
#include "nav/core/recovery/factor_preconditioner.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::core {
namespace {

struct Survey {
  InformationMatrix lambda{6};
  Eigen::VectorXd eta;
};

/// The lawnmower graph of about `states` poses (20 tracklines at 1k, 50 at 10k, 200 at 100k).
const Survey& survey(int states) {
  static std::map<int, std::unique_ptr<Survey>> cache;
  if (auto it = cache.find(states); it != cache.end()) return *it->second;
  const int rows = states <= 1000 ? 20 : states <= 10000 ? 50 : 200;
  const PoseGraph graph = bench::lawnmower_graph(rows, states / rows);
  auto s = std::make_unique<Survey>();
  s->lambda = assemble_information(graph);
  Eigen::VectorXd mean(s->lambda.dim());
  for (size_t v = 0; v < graph.vertices.size(); ++v) {
    mean.segment(6 * static_cast<Eigen::Index>(v), 6) = graph.vertices[v].pose;
  }
  s->eta = s->lambda.to_sparse() * mean;
  return *(cache[states] = std::move(s));
}

/// Adds a camera link (10 cm, ~1 deg) between the newest state and state `k`.
void add_link(InformationMatrix& lambda, int k) {
  Mat6 w = Mat6::Identity();
  w.topLeftCorner<3, 3>() *= 100.0;
  w.bottomRightCorner<3, 3>() *= 3.0e3;
  const int newest = lambda.num_blocks() - 1;
  lambda.add_to_block(k, k, w);
  lambda.add_to_block(k, newest, -w);
  lambda.add_to_block(newest, newest, w);
}

void BM_RecoveryToTolerance(benchmark::State& state, RecoveryPreconditioner preconditioner,
                            bool keep_factor_equal) {
  const Survey& s = survey(static_cast<int>(state.range(0)));
  InformationMatrix lambda = s.lambda;
  StateRecoveryOptions options;
  options.mode = RecoveryMode::kTolerance;
  options.relative_tolerance = 1e-6;
  options.max_iterations = 3000;
  options.preconditioner = preconditioner;
  options.refresh_interval = 10;
  options.keep_factor_equal = keep_factor_equal;
  StateRecovery recovery(6, options);
  (void)recovery.set_solution(Eigen::MatrixXd::Zero(lambda.dim(), 7));
  (void)recovery.solve(lambda, s.eta);  // cold start (and the first factor), untimed
  double iterations = 0.0, refreshes = 0.0, capped = 0.0;
  std::uint32_t draw = 12345;
  for (auto _ : state) {
    state.PauseTiming();
    draw = draw * 1664525u + 1013904223u;
    add_link(lambda, static_cast<int>(draw % static_cast<std::uint32_t>(lambda.num_blocks() - 1)));
    state.ResumeTiming();
    const RecoveryResult r = recovery.solve(lambda, s.eta);
    iterations += r.iterations;
    refreshes += r.refreshed ? 1.0 : 0.0;
    capped += r.hit_iteration_cap ? 1.0 : 0.0;
    if (!r.status.ok()) state.SkipWithError(r.status.message().c_str());
  }
  state.counters["iterations"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
  state.counters["refreshes"] = benchmark::Counter(refreshes, benchmark::Counter::kAvgIterations);
  state.counters["hit_cap"] = benchmark::Counter(capped, benchmark::Counter::kAvgIterations);
  state.counters["dim"] = static_cast<double>(lambda.dim());
}

void BM_FactorRefresh(benchmark::State& state) {
  const Survey& s = survey(static_cast<int>(state.range(0)));
  const Eigen::SparseMatrix<double> lambda = s.lambda.to_sparse();
  FactorPreconditioner factor;
  for (auto _ : state) {
    const Status status = factor.refresh(lambda, 6);
    if (!status.ok()) state.SkipWithError(status.message().c_str());
  }
  state.counters["dim"] = static_cast<double>(lambda.rows());
}

BENCHMARK_CAPTURE(BM_RecoveryToTolerance, block_jacobi, RecoveryPreconditioner::kBlockJacobi,
                  false)
    ->Arg(1000)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecoveryToTolerance, factor, RecoveryPreconditioner::kFactor, false)
    ->Arg(1000)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecoveryToTolerance, kept_factor, RecoveryPreconditioner::kFactor, true)
    ->Arg(1000)
    ->Arg(10000)
    ->Arg(100000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FactorRefresh)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace nav::core
