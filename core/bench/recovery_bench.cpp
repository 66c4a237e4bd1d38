// Cost of one state-recovery step (recovery/state_recovery.h) at full map size, to check that
// it grows at most linearly with the map: BM_RecoveryStep/<graph> runs the real-time mode
// (warm-started block-Jacobi PCG, fixed iterations, true residual, preconditioner refactored)
// on the final information matrix of sphere2500, parking-garage and a synthetic lawnmower pose
// graph ten times the size of parking-garage. Counters: state dimension, ns per dimension.
// Each timed step first changes Λ like a filter step does (a link between states 0 and 1:
// three blocks, two of them diagonal; untimed), so the packed kernel's incremental
// preconditioner does the work it does in a replay. BM_RecoveryStep runs the packed kernel
// (packed_pcg.h, the default), BM_RecoveryStepGeneric the original pcg.h path on the same
// matrices in the same run: their ratio is the speed-up, robust to the machine's load.
// Also: the operator choice (packed / InformationMatrix::multiply / a CSR snapshot, and the
// snapshot cost) and one bounds update (propose + Joseph + fallback candidates).
#include <benchmark/benchmark.h>

#include <unsupported/Eigen/KroneckerProduct>

#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "nav/core/geometry/pose.h"
#include "nav/core/posegraph/g2o.h"
#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/packed_pcg.h"
#include "nav/core/recovery/pcg.h"
#include "nav/core/recovery/state_recovery.h"
#include "lawnmower_graph.h"

namespace nav::core {
namespace {

struct Problem {
  InformationMatrix lambda{6};
  CsrMatrix csr;
  Eigen::VectorXd eta;
};

/// Loads (once) the named graph's information matrix; nullptr if its data file is absent.
const Problem* problem(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Problem>> cache;
  if (auto it = cache.find(name); it != cache.end()) return it->second.get();
  PoseGraph graph;
  if (name == "lawnmower-20k") {
    graph = bench::lawnmower_graph(100, 200);
  } else {
    const auto path = std::filesystem::path(NAV_DATA_DIR) / "posegraphs" / (name + ".g2o");
    if (!std::filesystem::exists(path)) return nullptr;
    graph = read_g2o(path.string());
  }
  auto p = std::make_unique<Problem>();
  p->lambda = assemble_information(graph);
  p->csr = p->lambda.to_sparse();
  Eigen::VectorXd mean(p->lambda.dim());
  for (size_t v = 0; v < graph.vertices.size(); ++v) {
    mean.segment(6 * static_cast<Eigen::Index>(v), 6) = graph.vertices[v].pose;
  }
  p->eta = p->csr * mean;
  return (cache[name] = std::move(p)).get();
}

/// The named graph's Λ lifted to 12-dimensional states, as the vehicle filter's (pose and
/// velocity): every 6 x 6 block B becomes B ⊗ [2 1; 1 2] (SPD stays SPD, the block pattern is
/// the graph's). Only the pattern and the block size matter to the kernels timed with it.
const InformationMatrix* lifted12(const std::string& name) {
  static std::map<std::string, std::unique_ptr<InformationMatrix>> cache;
  if (auto it = cache.find(name); it != cache.end()) return it->second.get();
  const Problem* p = problem(name);
  if (p == nullptr) return nullptr;
  Eigen::Matrix2d S;
  S << 2.0, 1.0, 1.0, 2.0;
  const auto lift = [&](const Eigen::MatrixXd& B) { return Eigen::MatrixXd(kroneckerProduct(B, S)); };
  auto out = std::make_unique<InformationMatrix>(12);
  for (int b = 0; b < p->lambda.num_blocks(); ++b) out->add_block();
  for (int i = 0; i < p->lambda.num_blocks(); ++i) {
    out->add_to_block(i, i, lift(p->lambda.diagonal_block(i)));
    for (int k = 0; k < p->lambda.num_neighbours(i); ++k) {
      const int j = p->lambda.neighbour(i, k);
      if (j > i) out->add_to_block(i, j, lift(p->lambda.neighbour_block(i, k)));
    }
  }
  return (cache[name] = std::move(out)).get();
}

void set_counters(benchmark::State& state, Eigen::Index dim) {
  state.counters["dim"] = static_cast<double>(dim);
  state.counters["ns_per_dim"] = benchmark::Counter(
      1e-9 * static_cast<double>(dim),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

enum class StepKernel { kPacked, kGeneric, kCsr };

/// One real-time recovery step: K PCG iterations from the previous step's solution, after a
/// small link update of Λ between states 0 and 1 (untimed).
void BM_RecoveryStep(benchmark::State& state, const std::string& name, StepKernel kernel) {
  const Problem* p = problem(name);
  if (p == nullptr) {
    state.SkipWithError("pose graph data file absent");
    return;
  }
  InformationMatrix lambda = p->lambda;
  StateRecoveryOptions options;
  options.iterations_per_step = static_cast<int>(state.range(0));
  options.kernel =
      kernel == StepKernel::kPacked ? RecoveryKernel::kPacked : RecoveryKernel::kGeneric;
  options.preconditioner = RecoveryPreconditioner::kBlockJacobi;  // the real-time default
  StateRecovery recovery(6, options);
  (void)recovery.set_solution(Eigen::MatrixXd::Zero(lambda.dim(), 7));
  const Mat6 link = Mat6::Identity() * 1e-3;
  double refactored = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    lambda.add_to_block(0, 0, link);
    lambda.add_to_block(0, 1, -link);
    lambda.add_to_block(1, 1, link);
    const CsrMatrix csr = kernel == StepKernel::kCsr ? CsrMatrix(lambda.to_sparse()) : CsrMatrix();
    state.ResumeTiming();
    const RecoveryResult r =
        kernel == StepKernel::kCsr ? recovery.solve(csr, p->eta) : recovery.solve(lambda, p->eta);
    refactored += r.refactored_blocks;
    benchmark::DoNotOptimize(r.max_relative_residual);
  }
  set_counters(state, lambda.dim());
  state.counters["refactored_blocks"] =
      benchmark::Counter(refactored, benchmark::Counter::kAvgIterations);
}

/// Y = Λ X with `columns` random columns packed (packed_pcg.h), Λ read in place.
void time_packed_multiply(benchmark::State& state, const InformationMatrix* lambda, int columns) {
  if (lambda == nullptr) {
    state.SkipWithError("pose graph data file absent");
    return;
  }
  PackedBlockOperator op;
  op.refresh(*lambda);
  const int width = packed_width(columns);
  std::vector<double> x, y(static_cast<size_t>(lambda->dim() * width));
  pack_columns(Eigen::MatrixXd::Random(lambda->dim(), columns), width, &x);
  for (auto _ : state) {
    op.multiply(x.data(), y.data(), width);
    benchmark::DoNotOptimize(y.data());
  }
  set_counters(state, lambda->dim());
}

/// The pose graph's Λ by 7 columns (packed width 8).
void BM_MultiplyPacked(benchmark::State& state, const std::string& name) {
  const Problem* p = problem(name);
  time_packed_multiply(state, p != nullptr ? &p->lambda : nullptr, 7);
}

/// The same on the 12-dimensional lift (13 columns: μ and Σ_{*r}, packed width 16).
void BM_MultiplyPacked12(benchmark::State& state, const std::string& name) {
  time_packed_multiply(state, lifted12(name), 13);
}

void BM_Multiply(benchmark::State& state, const std::string& name, bool use_csr) {
  const Problem* p = problem(name);
  if (p == nullptr) {
    state.SkipWithError("pose graph data file absent");
    return;
  }
  const Eigen::MatrixXd X = Eigen::MatrixXd::Random(p->lambda.dim(), 7);
  Eigen::MatrixXd Y(p->lambda.dim(), 7);
  for (auto _ : state) {
    if (use_csr) {
      CsrOperator(p->csr).multiply(X, Y);
    } else {
      p->lambda.multiply(X, Y);
    }
    benchmark::DoNotOptimize(Y.data());
  }
  set_counters(state, p->lambda.dim());
}

void BM_CsrSnapshot(benchmark::State& state, const std::string& name) {
  const Problem* p = problem(name);
  if (p == nullptr) {
    state.SkipWithError("pose graph data file absent");
    return;
  }
  for (auto _ : state) {
    const CsrMatrix snapshot = p->lambda.to_sparse();
    benchmark::DoNotOptimize(snapshot.nonZeros());
  }
  set_counters(state, p->lambda.dim());
}

void BM_BoundsUpdate(benchmark::State& state) {
  CovarianceBounds bounds(6);
  (void)bounds.initialize_robot(Mat6::Identity());
  (void)bounds.insert(1);
  (void)bounds.set_recovery(Mat6::Identity() * 0.5, 1e-3, 2);
  const Mat6 sigma_ir = Mat6::Identity() * 0.1;
  const Eigen::MatrixXd H_r = -Mat6::Identity(), H_i = Mat6::Identity();
  const Eigen::MatrixXd R = Mat6::Identity() * 0.01;
  for (auto _ : state) {
    LinkProposal proposal;
    (void)bounds.propose(1, sigma_ir, &proposal);
    const Status s = bounds.update(proposal, H_r, H_i, R);
    benchmark::DoNotOptimize(s.ok());
  }
}

const int kRegistered = [] {
  for (const std::string name : {"sphere2500", "parking-garage", "lawnmower-20k"}) {
    benchmark::RegisterBenchmark(("BM_RecoveryStep/" + name).c_str(), BM_RecoveryStep, name,
                                 StepKernel::kPacked)
        ->Arg(5)
        ->Arg(3)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_RecoveryStepGeneric/" + name).c_str(), BM_RecoveryStep,
                                 name, StepKernel::kGeneric)
        ->Arg(5)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_RecoveryStepCsr/" + name).c_str(), BM_RecoveryStep, name,
                                 StepKernel::kCsr)
        ->Arg(5)
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_MultiplyPacked/" + name).c_str(), BM_MultiplyPacked, name)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("BM_MultiplyPacked12/" + name).c_str(), BM_MultiplyPacked12,
                                 name)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("BM_MultiplyBlocks/" + name).c_str(), BM_Multiply, name, false)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("BM_MultiplyCsr/" + name).c_str(), BM_Multiply, name, true)
        ->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("BM_CsrSnapshot/" + name).c_str(), BM_CsrSnapshot, name)
        ->Unit(benchmark::kMicrosecond);
  }
  benchmark::RegisterBenchmark("BM_BoundsUpdate", BM_BoundsUpdate)
      ->Unit(benchmark::kMicrosecond);
  return 0;
}();

}  // namespace
}  // namespace nav::core
