// navd's vision stage: thread pool registering proposed pairs (vision/vision_worker.h).
#include "nav/daemon/vision/vision_worker.h"

#include <stdexcept>
#include <utility>

#include "nav/daemon/system/host_clock.h"

namespace nav::daemon::vision {
namespace {

double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

std::string pair_name(const VisionRequest& r) {
  return "pair " + std::to_string(r.frame_i) + "-" + std::to_string(r.frame_j);
}

}  // namespace

VisionWorker::VisionWorker(const nav::vision::Registration& registration, FrameLoader loader,
                           FeatureCache& cache, AnswerSink sink, VisionWorkerOptions options)
    : registration_(registration),
      loader_(std::move(loader)),
      cache_(cache),
      sink_(std::move(sink)),
      options_(std::move(options)) {
  if (options_.threads < 1 || options_.threads > 64) {
    throw std::invalid_argument("VisionWorker: threads " + std::to_string(options_.threads) +
                                " is not in [1, 64]");
  }
  if (options_.queue_capacity == 0) {
    throw std::invalid_argument("VisionWorker: queue_capacity must be >= 1");
  }
  for (int t = 0; t < options_.threads; ++t) threads_.emplace_back([this] { run(); });
}

VisionWorker::~VisionWorker() { stop(); }

std::int64_t VisionWorker::now_us() const {
  return options_.now_realtime_us ? options_.now_realtime_us() : realtime_us();
}

void VisionWorker::submit(VisionRequest request) {
  std::optional<Item> evicted;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    ++counters_.submitted;
    if (options_.overflow == Overflow::kBlock) {
      room_.wait(lock, [&] { return stopping_ || queue_.size() < options_.queue_capacity; });
    } else if (queue_.size() >= options_.queue_capacity) {
      evicted = std::move(queue_.front());
      queue_.pop_front();
    }
    queue_.push_back(Item{std::move(request), std::chrono::steady_clock::now()});
    counters_.queue_depth = queue_.size();
  }
  work_ready_.notify_one();
  if (evicted) deliver(failure(*evicted, "expired: queue full (worker behind)", true));
}

void VisionWorker::stop() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  work_ready_.notify_all();
  room_.notify_all();
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
  threads_.clear();
}

void VisionWorker::run() {
  for (;;) {
    Item item;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_ready_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      item = std::move(queue_.front());
      queue_.pop_front();
      counters_.queue_depth = queue_.size();
    }
    room_.notify_one();
    const std::int64_t deadline = item.request.deadline_realtime_us;
    if (deadline > 0 && now_us() > deadline) {
      deliver(failure(item,
                      "expired: deadline passed " +
                          std::to_string((now_us() - deadline) / 1000) + " ms before work began",
                      true));
      continue;
    }
    VisionAnswer answer;
    try {
      answer = work(item);
    } catch (const std::exception& e) {
      answer = failure(item, std::string("worker exception: ") + e.what(), false);
    } catch (...) {
      answer = failure(item, "worker exception: unknown", false);
    }
    deliver(std::move(answer));
  }
}

std::shared_ptr<const CachedFeatures> VisionWorker::features(std::uint64_t frame_id) {
  return cache_.get(frame_id, [this](std::uint64_t id) {
    CachedFeatures out;
    cv::Mat image;
    try {
      image = loader_(id);
    } catch (const std::exception& e) {
      out.error = "frame " + std::to_string(id) + ": " + e.what();
      return out;
    }
    if (const core::Status s = registration_.try_features(image, &out.features); !s.ok()) {
      out.error = "frame " + std::to_string(id) + ": " + s.message();
      return out;
    }
    out.ok = true;
    return out;
  });
}

VisionAnswer VisionWorker::work(const Item& item) {
  const VisionRequest& r = item.request;
  const std::shared_ptr<const CachedFeatures> fi = features(r.frame_i);
  if (!fi->ok) return failure(item, fi->error, false);
  const std::shared_ptr<const CachedFeatures> fj = features(r.frame_j);
  if (!fj->ok) return failure(item, fj->error, false);
  const nav::vision::RegistrationResult result =
      registration_.register_pair(fi->features, fj->features, r.prior ? &*r.prior : nullptr);
  VisionAnswer answer;
  if (!result.success) {
    answer = failure(item, pair_name(r) + ": " + result.reason, false);
  } else {
    answer.request = r;
    answer.registration.frame_id_i = static_cast<std::int64_t>(r.frame_i);
    answer.registration.frame_id_j = static_cast<std::int64_t>(r.frame_j);
    answer.registration.success = true;
    answer.registration.z = result.z;
    answer.registration.covariance = result.covariance;
    answer.latency_ms = ms_since(item.submitted);
  }
  answer.inliers = result.inliers;
  answer.max_leverage = result.max_leverage;
  return answer;
}

VisionAnswer VisionWorker::failure(const Item& item, std::string reason, bool expired) const {
  VisionAnswer answer;
  answer.request = item.request;
  answer.registration.frame_id_i = static_cast<std::int64_t>(item.request.frame_i);
  answer.registration.frame_id_j = static_cast<std::int64_t>(item.request.frame_j);
  answer.registration.success = false;
  answer.reason = std::move(reason);
  answer.expired = expired;
  answer.latency_ms = ms_since(item.submitted);
  return answer;
}

void VisionWorker::deliver(VisionAnswer&& answer) {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    ++counters_.answered;
    if (answer.registration.success) {
      ++counters_.succeeded;
    } else {
      ++counters_.failed;
      counters_.last_failure = answer.reason;
    }
    if (answer.expired) {
      ++counters_.expired;
    } else {
      ++worked_;
      latency_sum_ms_ += answer.latency_ms;
      counters_.latency_ms_mean = latency_sum_ms_ / static_cast<double>(worked_);
      counters_.latency_ms_max = std::max(counters_.latency_ms_max, answer.latency_ms);
    }
  }
  if (sink_) sink_(std::move(answer));
}

VisionWorkerCounters VisionWorker::counters() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return counters_;
}

}  // namespace nav::daemon::vision
