// ESDF per-operation cost against map size (Eustice, Singh & Leonard, ICRA 2005: predict and
// update are constant time in the number of delayed states). Maps of n 12-element delayed
// states are built once per n (outside the timing) and reused; only the operation is timed.
//   BM_EsdfPredict/<n>           predict + marginalise the robot (constant-velocity model)
//   BM_EsdfUpdateCameraLink/<n>  5-DOF camera link between two delayed states far apart
//   BM_EsdfAugment/<n>           predict keeping the robot as a new delayed state
// Flatness target: time(n = 100000) / time(n = 1000) < 2.
#include "nav/core/filter/esdf.h"
#include "nav/core/models/binary_models.h"
#include "nav/core/models/constant_velocity.h"

#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <numbers>
#include <stdexcept>

namespace nav::core {
namespace {

constexpr double kDt = 0.5;

/// A survey-like chain: n delayed states along a straight track line (1 m apart).
std::unique_ptr<Esdf> build_map(int n) {
  auto f = std::make_unique<Esdf>(12);
  Vec12 x0 = Vec12::Zero();
  x0[kHeading] = std::numbers::pi / 2;
  x0[kU] = 2.0;
  x0[kZ] = 10.0;
  if (!f->initialize(x0, 0.01 * Mat12::Identity()).ok()) throw std::runtime_error("init");
  const ConstantVelocityModel model;
  for (int k = 0; k < n; ++k) {
    if (!f->predict(model, kDt, true).ok()) throw std::runtime_error("predict");
  }
  return f;
}

Esdf& map_of_size(int n) {
  static std::map<int, std::unique_ptr<Esdf>> maps;
  auto it = maps.find(n);
  if (it == maps.end()) it = maps.emplace(n, build_map(n)).first;
  return *it->second;
}

void BM_EsdfPredict(benchmark::State& state) {
  Esdf& f = map_of_size(static_cast<int>(state.range(0)));
  const ConstantVelocityModel model;
  for (auto _ : state) {
    const Status s = f.predict(model, kDt, false);
    benchmark::DoNotOptimize(&s);
  }
  state.counters["blocks_written"] = f.last_stats().blocks_written;
  state.counters["states"] = f.num_blocks();
}

void BM_EsdfUpdateCameraLink(benchmark::State& state) {
  Esdf& f = map_of_size(static_cast<int>(state.range(0)));
  const int n = f.num_blocks() - 1;
  CameraRelativePoseModel cam;
  cam.x_body_camera << 0, 0, 0, 0, 0, std::numbers::pi / 2;
  MeasCov R = MeasCov::Identity(5, 5) * 1e-4;
  // 64 fixed loop-closure pairs spread over the whole map (each pair's block is created on
  // first use, then updated): state i and i - 3.
  constexpr int kPairs = 64;
  int pairs[kPairs][2];
  for (int k = 0; k < kPairs; ++k) {
    const int b = 4 + static_cast<int>((static_cast<long long>(n - 4) * k) / kPairs);
    pairs[k][0] = b;
    pairs[k][1] = b - 3;
  }
  MeasVec z[kPairs];
  for (int k = 0; k < kPairs; ++k) {
    z[k] = cam.predict(f.mean_block(pairs[k][1]), f.mean_block(pairs[k][0]));
  }
  int k = 0;
  for (auto _ : state) {
    const Status s = f.update(cam, pairs[k][1], pairs[k][0], z[k], R);
    if (!s.ok()) state.SkipWithError(s.to_string().c_str());
    k = (k + 1) % kPairs;
  }
  state.counters["blocks_written"] = f.last_stats().blocks_written;
  state.counters["states"] = f.num_blocks();
}

void BM_EsdfAugment(benchmark::State& state) {
  Esdf& f = map_of_size(static_cast<int>(state.range(0)));
  const ConstantVelocityModel model;
  for (auto _ : state) {
    const Status s = f.predict(model, kDt, true);
    benchmark::DoNotOptimize(&s);
  }
  state.counters["blocks_written"] = f.last_stats().blocks_written;
}

BENCHMARK(BM_EsdfPredict)->Arg(1000)->Arg(10000)->Arg(100000);
BENCHMARK(BM_EsdfUpdateCameraLink)->Arg(1000)->Arg(10000)->Arg(100000);
// Last: it grows the shared maps (by the iteration count).
BENCHMARK(BM_EsdfAugment)->Arg(1000)->Arg(10000)->Arg(100000);

}  // namespace
}  // namespace nav::core
