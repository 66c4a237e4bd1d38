// Cost of the per-measurement geometry on the filter's real-time path: SSC compounding with
// analytic Jacobians (geometry/pose.h), the measurement models' predict + H
// (models/*_models.h) and one constant-velocity prediction with F and Q
// (models/constant_velocity.h). Numbers are per call.

#include <benchmark/benchmark.h>

#include "nav/core/geometry/pose.h"
#include "nav/core/models/binary_models.h"
#include "nav/core/models/constant_velocity.h"
#include "nav/core/models/unary_models.h"

namespace {

using namespace nav::core;

Vec6 pose_a() {
  Vec6 x;
  x << 1, 2, 3, 0.1, 0.2, 0.3;
  return x;
}

Vec6 pose_b() {
  Vec6 x;
  x << 4, 1, 3.5, 0.15, 0.1, 0.45;
  return x;
}

Vec12 state(const Vec6& pose) {
  Vec12 x;
  x << pose, 1.0, 0.1, 0.0, 0.01, 0.02, 0.03;
  return x;
}

void BM_HeadToTail(benchmark::State& s, bool jacobian) {
  const Vec6 a = pose_a(), b = pose_b();
  Mat6x12 J;
  for (auto _ : s) benchmark::DoNotOptimize(head_to_tail(a, b, jacobian ? &J : nullptr));
}
BENCHMARK_CAPTURE(BM_HeadToTail, value, false);
BENCHMARK_CAPTURE(BM_HeadToTail, with_jacobian, true);

void BM_TailToTail(benchmark::State& s, bool jacobian) {
  const Vec6 a = pose_a(), b = pose_b();
  Mat6x12 J;
  for (auto _ : s) benchmark::DoNotOptimize(tail_to_tail(a, b, jacobian ? &J : nullptr));
}
BENCHMARK_CAPTURE(BM_TailToTail, value, false);
BENCHMARK_CAPTURE(BM_TailToTail, with_jacobian, true);

void BM_DvlPredict(benchmark::State& s) {
  DvlVelocityModel dvl;
  dvl.p_body_dvl_m << 1.0, 0.2, 0.3;
  const Vec12 x = state(pose_a());
  MeasJac H;
  for (auto _ : s) benchmark::DoNotOptimize(dvl.predict(x, &H));
}
BENCHMARK(BM_DvlPredict);

void BM_DepthPredict(benchmark::State& s) {
  DepthModel depth;
  depth.p_body_sensor_m << 0.5, 0.0, 0.1;
  const Vec12 x = state(pose_a());
  MeasJac H;
  for (auto _ : s) benchmark::DoNotOptimize(depth.predict(x, &H));
}
BENCHMARK(BM_DepthPredict);

void BM_RelativePose6Predict(benchmark::State& s) {
  const Vec12 a = state(pose_a()), b = state(pose_b());
  MeasJac H_a, H_b;
  for (auto _ : s) benchmark::DoNotOptimize(RelativePose6Model{}.predict(a, b, &H_a, &H_b));
}
BENCHMARK(BM_RelativePose6Predict);

void BM_CameraRelativePosePredict(benchmark::State& s) {
  CameraRelativePoseModel camera;
  camera.x_body_camera << 0.5, 0.0, 0.3, 0.0, 0.0, 1.5707963;
  const Vec12 a = state(pose_a()), b = state(pose_b());
  MeasJac H_a, H_b;
  for (auto _ : s) benchmark::DoNotOptimize(camera.predict(a, b, &H_a, &H_b));
}
BENCHMARK(BM_CameraRelativePosePredict);

void BM_ConstantVelocityPredictFQ(benchmark::State& s) {
  const ConstantVelocityModel model;
  const Vec12 x = state(pose_a());
  Mat12 F;
  for (auto _ : s) {
    benchmark::DoNotOptimize(model.predict(x, 0.1, &F));
    benchmark::DoNotOptimize(model.process_noise(x, 0.1));
  }
}
BENCHMARK(BM_ConstantVelocityPredictFQ);

}  // namespace
