// nav_vision benchmarks on one core (OpenCV's thread pool is set to one thread): features of a
// 1280x1024 12-bit frame (the simulator's Mono12 camera) and the registration of one pair.
// The 12-bit frames are real Sparus seafloor frames resampled to 1280x1024 under a strobe-like
// falloff (the real frames are 384x288 8-bit); without the data folder the benchmarks skip.
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "nav/vision/registration.h"
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
  RegistrationResult r;
  for (auto _ : state) {
    r = registration.register_pair(fa, fb, nullptr);
    benchmark::DoNotOptimize(r);
  }
  state.counters["inliers"] = r.inliers;
  state.counters["putative"] = r.putative_matches;
  state.counters["success"] = r.success ? 1 : 0;
}
BENCHMARK(BM_RegisterPair1280x1024)
    ->Arg(static_cast<int>(RobustMethod::kLmeds))
    ->Arg(static_cast<int>(RobustMethod::kRansac))
    ->Arg(static_cast<int>(RobustMethod::kUsacMagsac))
    ->Unit(benchmark::kMillisecond);

}  // namespace
