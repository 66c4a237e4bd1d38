// nav_vision benchmarks on one core (OpenCV's thread pool is set to one thread): features of a
// 1280x1024 12-bit frame (the simulator's Mono12 camera) and the registration of one pair.
// The 12-bit frames are real Sparus seafloor frames resampled to 1280x1024 under a strobe-like
// falloff (the real frames are 384x288 8-bit); without the data folder the benchmarks skip.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "nav/vision/registration.h"
#include "nav/vision/relative_pose_5dof.h"
#include "test_cameras.h"

namespace {

using namespace nav::vision;

/// Sparus frame `name` as a 1280x1024 Mono12 strobe-lit frame; empty when the data is absent.
cv::Mat twelve_bit_frame(const std::string& name) {
  const std::filesystem::path path = std::filesystem::path(NAV_DATA_DIR) / "images/sparus" / name;
  const cv::Mat bgr = cv::imread(path.string(), cv::IMREAD_COLOR);
  if (bgr.empty()) return {};
  cv::Mat grey, big, f;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  cv::resize(grey, big, cv::Size(1280, 1024), 0, 0, cv::INTER_CUBIC);
  big.convertTo(f, CV_32F, 1.0 / 255.0);
  for (int r = 0; r < f.rows; ++r) {
    float* row = f.ptr<float>(r);
    for (int c = 0; c < f.cols; ++c) {
      const double dx = (c - 600.0) / 1280.0, dy = (r - 480.0) / 1280.0;
      row[c] *= static_cast<float>(std::exp(-(dx * dx + dy * dy) / 0.35));
    }
  }
  cv::Mat out;
  f.convertTo(out, CV_16U, 4095.0);
  return out;
}

void BM_Features1280x1024Mono12(benchmark::State& state) {
  cv::setNumThreads(1);
  const cv::Mat frame = twelve_bit_frame("frame_01.png");
  if (frame.empty()) {
    state.SkipWithError("shared data absent (NAV_DATA_DIR)");
    return;
  }
  const Registration registration(test::sim_camera());
  std::size_t n = 0;
  for (auto _ : state) {
    const ImageFeatures f = registration.features(frame);
    n = f.size();
    benchmark::DoNotOptimize(n);
  }
  state.counters["features"] = static_cast<double>(n);
}
BENCHMARK(BM_Features1280x1024Mono12)->Unit(benchmark::kMillisecond);

/// Times register_pair(fa, fb, prior) over the benchmark's iterations and reports the stage
/// times (mean ms) and the last result's counts as counters.
void time_register_pair(benchmark::State& state, const Registration& registration,
                        const ImageFeatures& fa, const ImageFeatures& fb,
                        const RelativePosePrior* prior) {
  RegistrationResult r;
  RegistrationDiagnostics d;
  StageTimings sum;
  for (auto _ : state) {
    r = registration.register_pair(fa, fb, prior, &d);
    benchmark::DoNotOptimize(r);
    sum.matching_ms += d.timings.matching_ms;
    sum.essential_ms += d.timings.essential_ms;
    sum.refinement_ms += d.timings.refinement_ms;
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["match_ms"] = sum.matching_ms / n;
  state.counters["lmeds_ms"] = sum.essential_ms / n;
  state.counters["refine_ms"] = sum.refinement_ms / n;
  state.counters["inliers"] = r.inliers;
  state.counters["putative"] = r.putative_matches;
  state.counters["comparisons"] = static_cast<double>(r.descriptor_comparisons);
  state.counters["success"] = r.success ? 1 : 0;
}

void BM_RegisterPair1280x1024(benchmark::State& state) {
  cv::setNumThreads(1);
  const cv::Mat a = twelve_bit_frame("frame_01.png"), b = twelve_bit_frame("frame_03.png");
  if (a.empty() || b.empty()) {
    state.SkipWithError("shared data absent (NAV_DATA_DIR)");
    return;
  }
  RegistrationOptions options;
  options.essential.method = static_cast<RobustMethod>(state.range(0));
  const Registration registration(test::sim_camera(), options);
  const ImageFeatures fa = registration.features(a), fb = registration.features(b);
  time_register_pair(state, registration, fa, fb, nullptr);
}
BENCHMARK(BM_RegisterPair1280x1024)
    ->Arg(static_cast<int>(RobustMethod::kLmeds))
    ->Arg(static_cast<int>(RobustMethod::kRansac))
    ->Arg(static_cast<int>(RobustMethod::kUsacMagsac))
    ->Unit(benchmark::kMillisecond);

/// A prior around the pair's own unconstrained registration (baseline length 1, the scene depth
/// the median triangulated one): the filter's prior of a revisit, for timing the
/// pose-constrained path (the search region's size, not its accuracy, sets the cost).
/// `broad`: sigma 0.22 baseline lengths and 1 deg; otherwise 0.05 and 0.3 deg (a filter's
/// prior between frames a few seconds apart).
RelativePosePrior prior_from_registration(const Registration& registration,
                                          const ImageFeatures& a, const ImageFeatures& b,
                                          bool broad = false) {
  RegistrationDiagnostics d;
  const RegistrationResult r = registration.register_pair(a, b, nullptr, &d);
  RelativePosePrior prior;
  if (!r.success || d.refinement.depths_i.empty()) return prior;
  std::vector<double> depths = d.refinement.depths_i;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  prior.x_i_j = relative_pose_from_z(r.z, 1.0);
  prior.covariance = Mat6::Zero();
  const double t2 = broad ? 0.05 : 0.0025, r2 = broad ? 3e-4 : 2.7e-5;
  prior.covariance.diagonal() << t2, t2, t2, r2, r2, r2;
  prior.scene_depth_m = depths[depths.size() / 2];
  prior.scene_depth_sigma_m = 0.25 * prior.scene_depth_m;
  return prior;
}

void BM_RegisterPairPccs1280x1024(benchmark::State& state) {
  cv::setNumThreads(1);
  const cv::Mat a = twelve_bit_frame("frame_01.png"), b = twelve_bit_frame("frame_03.png");
  if (a.empty() || b.empty()) {
    state.SkipWithError("shared data absent (NAV_DATA_DIR)");
    return;
  }
  const Registration registration(test::sim_camera());
  const ImageFeatures fa = registration.features(a), fb = registration.features(b);
  const RelativePosePrior prior = prior_from_registration(registration, fa, fb, state.range(0) == 1);
  if (prior.scene_depth_m <= 0.0) {
    state.SkipWithError("the unconstrained registration giving the prior failed");
    return;
  }
  time_register_pair(state, registration, fa, fb, &prior);
}
BENCHMARK(BM_RegisterPairPccs1280x1024)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

/// The correspondence search alone: all pairs (ratio + mutual, matching.h) against PCCS with
/// the prior of BM_RegisterPairPccs1280x1024 (arg 1) or a broad prior (arg 2).
void BM_Match1280x1024(benchmark::State& state) {
  cv::setNumThreads(1);
  const cv::Mat a = twelve_bit_frame("frame_01.png"), b = twelve_bit_frame("frame_03.png");
  if (a.empty() || b.empty()) {
    state.SkipWithError("shared data absent (NAV_DATA_DIR)");
    return;
  }
  const Registration registration(test::sim_camera());
  const ImageFeatures fa = registration.features(a), fb = registration.features(b);
  const RelativePosePrior prior = prior_from_registration(registration, fa, fb, state.range(0) == 2);
  PutativeMatches m;
  for (auto _ : state) {
    m = state.range(0) == 0
            ? match_unconstrained(fa, fb, registration.options().matching)
            : match_pose_constrained(fa, fb, registration.camera(), prior, registration.options().pccs);
    benchmark::DoNotOptimize(m);
  }
  state.counters["putative"] = static_cast<double>(m.matches.size());
  state.counters["comparisons"] = static_cast<double>(m.descriptor_comparisons);
}
BENCHMARK(BM_Match1280x1024)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace
