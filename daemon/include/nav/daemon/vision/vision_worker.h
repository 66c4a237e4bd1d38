#pragma once
// VisionWorker: navd's own vision stage, a pool of threads registering proposed camera pairs
// with nav::vision::Registration (Eustice et al., RSS 2005, sec. III-C) and answering every
// request, success or not.
//
// Contract:
// * submit() never blocks the filter thread in live mode (Overflow::kExpireOldest): the queue
//   holds at most queue_capacity requests; a request arriving at a full queue expires the OLDEST
//   queued one (answered success = false, "expired: queue full", counted) so the worker drops
//   stale work first when it falls behind. Replay (Overflow::kBlock) waits for room instead,
//   so no answer depends on thread timing.
// * A thread takes the oldest request; one whose deadline (host CLOCK_REALTIME, 0 = none) has
//   passed is answered success = false "deadline passed" (counted expired) without work.
//   Otherwise the features of both frames come from the FeatureCache (computed once per frame,
//   from the FrameLoader), then register_pair with the request's pose prior.
// * Every failure is an answer with the reason: a frame the loader cannot read (missing,
//   corrupt: the loader throws), a frame of the wrong size or depth (try_features), too few
//   features or inliers (RegistrationResult), and any exception thrown inside the work ("worker
//   exception: ..."). A failure never stops a thread.
// * The AnswerSink is called on a worker thread (or, for an overflow expiry, inside submit()),
//   one call per request, never under the worker's lock.
// Counters are readable from any thread (health_t).

#include <opencv2/core.hpp>

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "nav/core/navigation/registration_table.h"
#include "nav/daemon/vision/feature_cache.h"
#include "nav/vision/registration.h"

namespace nav::daemon::vision {

struct VisionRequest {
  std::uint64_t sequence = 0;              ///< the filter's pending-pair sequence
  std::uint64_t frame_i = 0, frame_j = 0;  ///< earlier, later image
  std::optional<nav::vision::RelativePosePrior> prior;  ///< none: unconstrained matching
  std::int64_t deadline_realtime_us = 0;   ///< 0: no deadline
};

struct VisionAnswer {
  VisionRequest request;
  core::Registration registration;  ///< available_us left 0: the sink decides
  std::string reason;               ///< why success == false ("" on success)
  bool expired = false;             ///< not worked on (queue full or deadline passed)
  double latency_ms = 0.0;          ///< submit() to answer, wall clock
  int inliers = 0;                  ///< of a registration that got that far, else 0
  double max_leverage = 0.0;        ///< its largest leverage of one inlier, else 0
};

enum class Overflow { kBlock, kExpireOldest };

struct VisionWorkerOptions {
  int threads = 1;                  ///< [1, 64]
  std::size_t queue_capacity = 64;  ///< >= 1
  Overflow overflow = Overflow::kExpireOldest;
  /// Host CLOCK_REALTIME, us (tests inject a clock); empty: the system clock.
  std::function<std::int64_t()> now_realtime_us;
};

struct VisionWorkerCounters {
  std::uint64_t submitted = 0, answered = 0, succeeded = 0, failed = 0, expired = 0;
  std::size_t queue_depth = 0;
  double latency_ms_mean = 0.0, latency_ms_max = 0.0;  ///< of the answers worked on
  std::string last_failure;  ///< reason of the newest failed answer
  double success_rate() const {
    return answered > 0 ? static_cast<double>(succeeded) / static_cast<double>(answered) : 0.0;
  }
};

class VisionWorker {
 public:
  /// The frame's pixels as read from disk; throws std::exception naming the file on failure.
  using FrameLoader = std::function<cv::Mat(std::uint64_t frame_id)>;
  using AnswerSink = std::function<void(VisionAnswer&&)>;

  /// Starts the threads. std::invalid_argument for threads outside [1, 64] or capacity 0.
  VisionWorker(const nav::vision::Registration& registration, FrameLoader loader,
               FeatureCache& cache, AnswerSink sink, VisionWorkerOptions options);
  ~VisionWorker();  ///< stop()
  VisionWorker(const VisionWorker&) = delete;
  VisionWorker& operator=(const VisionWorker&) = delete;

  void submit(VisionRequest request);
  /// Joins the threads after their current request; queued requests are dropped unanswered.
  void stop();
  VisionWorkerCounters counters() const;

 private:
  struct Item {
    VisionRequest request;
    std::chrono::steady_clock::time_point submitted;
  };
  void run();
  VisionAnswer work(const Item& item);
  VisionAnswer failure(const Item& item, std::string reason, bool expired) const;
  void deliver(VisionAnswer&& answer);
  std::shared_ptr<const CachedFeatures> features(std::uint64_t frame_id);
  std::int64_t now_us() const;

  const nav::vision::Registration& registration_;
  FrameLoader loader_;
  FeatureCache& cache_;
  AnswerSink sink_;
  VisionWorkerOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable work_ready_, room_;
  std::deque<Item> queue_;
  bool stopping_ = false;
  VisionWorkerCounters counters_;
  double latency_sum_ms_ = 0.0;
  std::uint64_t worked_ = 0;
  std::vector<std::thread> threads_;
};

}  // namespace nav::daemon::vision
