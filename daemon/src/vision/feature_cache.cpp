// Bounded feature cache (vision/feature_cache.h).
#include "nav/daemon/vision/feature_cache.h"

#include <algorithm>
#include <stdexcept>

namespace nav::daemon::vision {

std::size_t CachedFeatures::bytes() const {
  return features.descriptors.total() * features.descriptors.elemSize() +
         features.points_px.size() * (sizeof(Eigen::Vector2d) + sizeof(nav::vision::Detector));
}

FeatureCache::FeatureCache(std::size_t capacity) : capacity_(capacity) {
  if (capacity == 0) throw std::invalid_argument("FeatureCache: capacity must be >= 1");
}

std::shared_ptr<const CachedFeatures> FeatureCache::get(std::uint64_t frame_id,
                                                        const Compute& compute) {
  std::unique_lock<std::mutex> lock(mutex_);
  auto it = slots_.find(frame_id);
  if (it != slots_.end()) {
    ++counters_.hits;
    ready_.wait(lock, [&] {
      it = slots_.find(frame_id);
      return it == slots_.end() || it->second.value != nullptr;
    });
    if (it != slots_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      return it->second.value;
    }
    // The computing thread failed to publish (exception): compute here instead.
  }
  ++counters_.misses;
  lru_.push_front(frame_id);
  slots_[frame_id] = Slot{nullptr, lru_.begin()};
  lock.unlock();
  std::shared_ptr<const CachedFeatures> value;
  try {
    value = std::make_shared<const CachedFeatures>(compute(frame_id));
  } catch (...) {
    lock.lock();
    auto slot = slots_.find(frame_id);
    lru_.erase(slot->second.lru);
    slots_.erase(slot);
    ready_.notify_all();
    throw;
  }
  lock.lock();
  slots_[frame_id].value = value;
  counters_.bytes += value->bytes();
  counters_.peak_bytes = std::max(counters_.peak_bytes, counters_.bytes);
  evict_locked();
  counters_.entries = slots_.size();
  ready_.notify_all();
  return value;
}

void FeatureCache::evict_locked() {
  auto it = lru_.end();
  while (slots_.size() > capacity_ && it != lru_.begin()) {
    --it;
    auto slot = slots_.find(*it);
    if (slot->second.value == nullptr) continue;  // still computing
    counters_.bytes -= slot->second.value->bytes();
    ++counters_.evictions;
    slots_.erase(slot);
    it = lru_.erase(it);
  }
}

FeatureCacheCounters FeatureCache::counters() const {
  const std::lock_guard<std::mutex> lock(mutex_);
  return counters_;
}

}  // namespace nav::daemon::vision
