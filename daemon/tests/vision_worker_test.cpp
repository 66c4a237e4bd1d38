// navd's vision worker (vision/vision_worker.h, feature_cache.h, vision_link.h load_frame): every
// request is answered; bad input (missing or corrupt file, wrong frame size, an exception in
// the work) is a success = false answer with the reason, never a crash; a worker that falls
// behind expires the oldest requests (counted) and one past its deadline is not worked on.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <thread>
#include <vector>

#include "nav/daemon/sources/camera_source.h"
#include "nav/daemon/vision/vision_link.h"
#include "nav/daemon/vision/vision_worker.h"

namespace nav::daemon::vision {
namespace {

namespace fs = std::filesystem;

nav::vision::CameraIntrinsics camera(int width, int height) {
  nav::vision::CameraIntrinsics c;
  c.fx_px = c.fy_px = 200.0;
  c.cx_px = 80.0;
  c.cy_px = 64.0;
  c.width_px = width;
  c.height_px = height;
  return c;
}

/// Collects answers; wait(n) returns once n arrived (or fails after 30 s).
struct Answers {
  std::mutex mutex;
  std::condition_variable cv;
  std::vector<VisionAnswer> list;
  void add(VisionAnswer&& a) {
    const std::lock_guard<std::mutex> lock(mutex);
    list.push_back(std::move(a));
    cv.notify_all();
  }
  std::vector<VisionAnswer> wait(std::size_t n) {
    std::unique_lock<std::mutex> lock(mutex);
    EXPECT_TRUE(cv.wait_for(lock, std::chrono::seconds(30), [&] { return list.size() >= n; }))
        << list.size() << " of " << n << " answers";
    return list;
  }
};

VisionRequest request(std::uint64_t sequence, std::uint64_t i, std::uint64_t j) {
  VisionRequest r;
  r.sequence = sequence;
  r.frame_i = i;
  r.frame_j = j;
  return r;
}

cv::Mat textured(int width, int height) {
  cv::Mat m(height, width, CV_8UC1);
  cv::randu(m, 0, 255);
  return m;
}

TEST(VisionWorker, BadFramesAreAnsweredWithTheirReason) {
  const fs::path dir = fs::temp_directory_path() / ("vision_worker_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  cv::imwrite((dir / frame_png_name(1)).string(), textured(160, 128));
  cv::imwrite((dir / frame_png_name(2)).string(), textured(100, 90));  // wrong size
  std::ofstream(dir / frame_png_name(3)) << "not a png at all";        // corrupt
  // frame 4: missing
  const nav::vision::Registration registration(camera(160, 128));
  FeatureCache cache(8);
  Answers answers;
  VisionWorkerOptions o;
  o.threads = 2;
  VisionWorker worker(
      registration, [&](std::uint64_t id) { return load_frame(dir.string(), id); }, cache,
      [&](VisionAnswer&& a) { answers.add(std::move(a)); }, o);
  worker.submit(request(1, 1, 2));
  worker.submit(request(2, 1, 3));
  worker.submit(request(3, 1, 4));
  std::vector<VisionAnswer> got = answers.wait(3);
  std::sort(got.begin(), got.end(),
            [](const auto& a, const auto& b) { return a.request.sequence < b.request.sequence; });
  ASSERT_EQ(got.size(), 3u);
  for (const VisionAnswer& a : got) {
    EXPECT_FALSE(a.registration.success);
    EXPECT_FALSE(a.expired);
    EXPECT_EQ(a.registration.frame_id_i, 1);
  }
  EXPECT_NE(got[0].reason.find("frame 2"), std::string::npos) << got[0].reason;
  EXPECT_NE(got[0].reason.find("100"), std::string::npos) << "names the size: " << got[0].reason;
  EXPECT_NE(got[1].reason.find("frame 3: cannot read"), std::string::npos) << got[1].reason;
  EXPECT_NE(got[2].reason.find("frame 4: cannot read"), std::string::npos) << got[2].reason;
  const VisionWorkerCounters c = worker.counters();
  EXPECT_EQ(c.answered, 3u);
  EXPECT_EQ(c.failed, 3u);
  EXPECT_EQ(c.expired, 0u);
  EXPECT_FALSE(c.last_failure.empty());
  // Frame 1 was read once although three pairs used it.
  EXPECT_EQ(cache.counters().misses, 4u);
  EXPECT_EQ(cache.counters().hits, 2u);
  fs::remove_all(dir);
}

TEST(VisionWorker, ExceptionInTheWorkIsAnAnswerAndTheThreadGoesOn) {
  const nav::vision::Registration registration(camera(160, 128));
  FeatureCache cache(8);
  Answers answers;
  std::atomic<int> calls{0};
  VisionWorker worker(
      registration,
      [&](std::uint64_t id) -> cv::Mat {
        ++calls;
        if (id == 7) throw 42;  // not even a std::exception
        return textured(160, 128);
      },
      cache, [&](VisionAnswer&& a) { answers.add(std::move(a)); }, VisionWorkerOptions{});
  worker.submit(request(1, 7, 8));
  worker.submit(request(2, 8, 9));
  const std::vector<VisionAnswer> got = answers.wait(2);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].reason, "worker exception: unknown");
  EXPECT_FALSE(got[0].registration.success);
  // The same (only) thread worked on the next request after the exception.
  EXPECT_EQ(got[1].request.sequence, 2u);
  EXPECT_EQ(got[1].reason.find("worker exception"), std::string::npos) << got[1].reason;
  EXPECT_EQ(calls.load(), 3);
  EXPECT_EQ(worker.counters().answered, 2u);
}

TEST(VisionWorker, FallingBehindExpiresTheOldestAndPastDeadlinesAreNotWorkedOn) {
  const nav::vision::Registration registration(camera(160, 128));
  FeatureCache cache(8);
  Answers answers;
  std::mutex gate_mutex;
  std::condition_variable gate_cv;
  bool open = false;
  std::atomic<std::int64_t> now_us{1'000'000};
  VisionWorkerOptions o;
  o.queue_capacity = 2;
  o.now_realtime_us = [&] { return now_us.load(); };
  VisionWorker worker(
      registration,
      [&](std::uint64_t) {
        std::unique_lock<std::mutex> lock(gate_mutex);
        gate_cv.wait(lock, [&] { return open; });
        return textured(160, 128);
      },
      cache, [&](VisionAnswer&& a) { answers.add(std::move(a)); }, o);
  worker.submit(request(1, 1, 2));  // taken by the thread, blocks in the loader
  while (worker.counters().queue_depth != 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  for (std::uint64_t s = 2; s <= 5; ++s) {
    VisionRequest r = request(s, 10 * s, 10 * s + 1);
    r.deadline_realtime_us = 2'000'000;
    worker.submit(r);
  }
  // Queue of 2: requests 2 and 3 expired when 4 and 5 arrived.
  EXPECT_EQ(worker.counters().queue_depth, 2u);
  std::vector<VisionAnswer> got = answers.wait(2);
  EXPECT_EQ(got[0].request.sequence, 2u);
  EXPECT_EQ(got[1].request.sequence, 3u);
  EXPECT_TRUE(got[0].expired);
  EXPECT_EQ(got[0].reason, "expired: queue full (worker behind)");
  now_us = 2'500'000;  // 4 and 5 are now past their deadline
  {
    const std::lock_guard<std::mutex> lock(gate_mutex);
    open = true;
  }
  gate_cv.notify_all();
  got = answers.wait(5);
  ASSERT_EQ(got.size(), 5u);
  for (std::size_t k = 3; k < 5; ++k) {
    EXPECT_TRUE(got[k].expired);
    EXPECT_NE(got[k].reason.find("deadline passed 500 ms"), std::string::npos) << got[k].reason;
  }
  const VisionWorkerCounters c = worker.counters();
  EXPECT_EQ(c.expired, 4u);
  EXPECT_EQ(c.answered, 5u);
  EXPECT_EQ(c.queue_depth, 0u);
}

TEST(FeatureCache, KeepsAtMostCapacityEntriesLeastRecentlyUsedOut) {
  FeatureCache cache(2);
  std::vector<std::uint64_t> computed;
  auto compute = [&](std::uint64_t id) {
    computed.push_back(id);
    CachedFeatures f;
    f.ok = true;
    f.features.descriptors = cv::Mat::zeros(static_cast<int>(id), 128, CV_32F);
    f.features.points_px.resize(id);
    f.features.detector.resize(id);
    return f;
  };
  cache.get(1, compute);
  cache.get(2, compute);
  cache.get(1, compute);  // hit: 1 most recent
  cache.get(3, compute);  // evicts 2
  cache.get(1, compute);  // still cached
  cache.get(2, compute);  // recomputed
  EXPECT_EQ(computed, (std::vector<std::uint64_t>{1, 2, 3, 2}));
  const FeatureCacheCounters c = cache.counters();
  EXPECT_EQ(c.entries, 2u);
  EXPECT_EQ(c.evictions, 2u);
  EXPECT_EQ(c.bytes, (1 + 2) * (512 + sizeof(Eigen::Vector2d) + 1));
  EXPECT_THROW(FeatureCache(0), std::invalid_argument);
}

}  // namespace
}  // namespace nav::daemon::vision
