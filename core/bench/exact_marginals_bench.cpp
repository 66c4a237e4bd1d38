// Exact marginals (CHOLMOD + supernodal selected inversion) vs a dense inverse on the public
// pose graphs (recovery/exact_marginals.h). Targets: parking-garage (9,966 dims) all 1,661
// diagonal blocks <= 100 ms, sphere2500 (15,000 dims) <= 150 ms, >= 100x faster than the
// dense LLT inverse of the same matrix. Counters: factor_ms, inversion_ms, nnz_L.
// BM_FactorSolve: X = Λ⁻¹ B with 13 columns (the recovery's [η | E_r], the factor
// preconditioner's apply) by ExactMarginals::solve against CHOLMOD's own supernodal solve of a
// factor with the same (CHOLMOD default) ordering.

#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <Eigen/CholmodSupport>
#include <Eigen/Dense>
#include <filesystem>
#include <map>
#include <string>

#include "nav/core/posegraph/g2o.h"
#include "nav/core/recovery/exact_marginals.h"

namespace {

using nav::core::ExactMarginals;

/// Lambda of a graph in the data folder, cached; nullptr if the file is absent.
const Eigen::SparseMatrix<double>* information_of(const std::string& graph) {
  static std::map<std::string, Eigen::SparseMatrix<double>> cache;
  const auto it = cache.find(graph);
  if (it != cache.end()) return &it->second;
  const std::filesystem::path path =
      std::filesystem::path(NAV_DATA_DIR) / "posegraphs" / (graph + ".g2o");
  if (!std::filesystem::exists(path)) return nullptr;
  const auto pg = nav::core::read_g2o(path.string());
  return &cache.emplace(graph, nav::core::assemble_information_sparse(pg)).first->second;
}

void BM_ExactMarginals(benchmark::State& state, const std::string& graph,
                       nav::core::MarginalsOrdering ordering,
                       nav::core::MarginalsKernel kernel = nav::core::MarginalsKernel::kAuto) {
  const Eigen::SparseMatrix<double>* Lambda = information_of(graph);
  if (Lambda == nullptr) {
    state.SkipWithError(("data file posegraphs/" + graph + ".g2o absent").c_str());
    return;
  }
  double factor_ms = 0.0, inversion_ms = 0.0, nnz = 0.0, checksum = 0.0;
  for (auto _ : state) {
    const ExactMarginals em = ExactMarginals::compute(*Lambda, 6, ordering, kernel);
    // Read every diagonal block, as a consumer would.
    for (int b = 0; b < em.num_blocks(); ++b) checksum += em.marginal(b).trace();
    factor_ms = em.factor_ms();
    inversion_ms = em.inversion_ms();
    nnz = static_cast<double>(em.factor_nnz());
  }
  benchmark::DoNotOptimize(checksum);
  state.counters["dims"] = static_cast<double>(Lambda->rows());
  state.counters["factor_ms"] = factor_ms;
  state.counters["inversion_ms"] = inversion_ms;
  state.counters["nnz_L"] = nnz;
  state.SetLabel(kernel == nav::core::MarginalsKernel::kBaseline
                     ? "baseline"
                     : nav::core::auto_marginals_kernel_name());
}

void BM_DenseInverse(benchmark::State& state, const std::string& graph) {
  const Eigen::SparseMatrix<double>* Lambda = information_of(graph);
  if (Lambda == nullptr) {
    state.SkipWithError(("data file posegraphs/" + graph + ".g2o absent").c_str());
    return;
  }
  double checksum = 0.0;
  for (auto _ : state) {
    const Eigen::MatrixXd dense(*Lambda);
    const Eigen::MatrixXd S =
        dense.llt().solve(Eigen::MatrixXd::Identity(dense.rows(), dense.cols()));
    checksum += S.diagonal().sum();
  }
  benchmark::DoNotOptimize(checksum);
  state.counters["dims"] = static_cast<double>(Lambda->rows());
}

enum class Solver { kOurs, kOursBaseline, kCholmod };

void BM_FactorSolve(benchmark::State& state, const std::string& graph, Solver solver) {
  const Eigen::SparseMatrix<double>* Lambda = information_of(graph);
  if (Lambda == nullptr) {
    state.SkipWithError(("data file posegraphs/" + graph + ".g2o absent").c_str());
    return;
  }
  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(Lambda->rows(), 13);
  Eigen::MatrixXd X(B.rows(), B.cols());
  if (solver == Solver::kCholmod) {
    const Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt(*Lambda);
    for (auto _ : state) {
      X = llt.solve(B);
      benchmark::DoNotOptimize(X.data());
    }
  } else {
    const ExactMarginals em = ExactMarginals::compute(
        *Lambda, 6, nav::core::MarginalsOrdering::kCholmodAuto,
        solver == Solver::kOursBaseline ? nav::core::MarginalsKernel::kBaseline
                                        : nav::core::MarginalsKernel::kAuto);
    for (auto _ : state) {
      em.solve(B, X);
      benchmark::DoNotOptimize(X.data());
    }
  }
  state.counters["relative_residual"] = (B - *Lambda * X).norm() / B.norm();
}

using nav::core::MarginalsOrdering;

BENCHMARK_CAPTURE(BM_ExactMarginals, smallGrid3D, std::string("smallGrid3D"),
                  MarginalsOrdering::kBlockAmd)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ExactMarginals, parking_garage, std::string("parking-garage"),
                  MarginalsOrdering::kBlockAmd)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ExactMarginals, sphere2500, std::string("sphere2500"),
                  MarginalsOrdering::kBlockAmd)
    ->Unit(benchmark::kMillisecond);
// Same AMD ordering with the baseline (SSE2) dense kernels: the runtime-dispatch speed-up.
BENCHMARK_CAPTURE(BM_ExactMarginals, parking_garage_baseline_kernel, std::string("parking-garage"),
                  MarginalsOrdering::kBlockAmd, nav::core::MarginalsKernel::kBaseline)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ExactMarginals, sphere2500_baseline_kernel, std::string("sphere2500"),
                  MarginalsOrdering::kBlockAmd, nav::core::MarginalsKernel::kBaseline)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ExactMarginals, parking_garage_cholmod_ordering, std::string("parking-garage"),
                  MarginalsOrdering::kCholmodAuto)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ExactMarginals, sphere2500_cholmod_ordering, std::string("sphere2500"),
                  MarginalsOrdering::kCholmodAuto)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ExactMarginals, parking_garage_block_metis, std::string("parking-garage"),
                  MarginalsOrdering::kBlockMetis)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ExactMarginals, sphere2500_block_metis, std::string("sphere2500"),
                  MarginalsOrdering::kBlockMetis)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FactorSolve, parking_garage_ours, std::string("parking-garage"),
                  Solver::kOurs)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FactorSolve, parking_garage_ours_baseline_kernel,
                  std::string("parking-garage"), Solver::kOursBaseline)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FactorSolve, parking_garage_cholmod, std::string("parking-garage"),
                  Solver::kCholmod)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FactorSolve, sphere2500_ours, std::string("sphere2500"), Solver::kOurs)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FactorSolve, sphere2500_cholmod, std::string("sphere2500"),
                  Solver::kCholmod)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_DenseInverse, smallGrid3D, std::string("smallGrid3D"))
    ->Unit(benchmark::kMillisecond);
// 9,966^2 dense LLT + identity solve: about a minute on one core, ~2.4 GB.
BENCHMARK_CAPTURE(BM_DenseInverse, parking_garage, std::string("parking-garage"))
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace
