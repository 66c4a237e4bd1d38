#pragma once
// Features of each camera frame, computed once and shared by every pair that uses the frame
// (nav::vision::Registration: features once per image, then pairs), in a bounded cache.
//
// Contract: get(frame, compute) returns the frame's entry, calling compute at most once per
// frame while the entry is cached, even when several threads ask at the same time (the others
// wait for the first). An entry holds the features or the reason they could not be computed (a
// missing or corrupt file fails every pair of that frame with the same reason, without reading
// it again). At most `capacity` entries are kept: inserting beyond evicts the least recently
// used finished entry (a pair still holding it keeps its shared_ptr). Thread-safe; compute runs
// outside the lock. Memory: about bytes() (descriptors 512 B + points 17 B per feature).

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

#include "nav/vision/vision_types.h"

namespace nav::daemon::vision {

struct CachedFeatures {
  bool ok = false;
  std::string error;  ///< why not ok: names the frame and the cause
  nav::vision::ImageFeatures features;
  std::size_t bytes() const;
};

struct FeatureCacheCounters {
  std::uint64_t hits = 0, misses = 0, evictions = 0;
  std::size_t entries = 0, bytes = 0, peak_bytes = 0;
};

class FeatureCache {
 public:
  using Compute = std::function<CachedFeatures(std::uint64_t frame_id)>;
  /// capacity >= 1 (std::invalid_argument otherwise).
  explicit FeatureCache(std::size_t capacity);
  std::shared_ptr<const CachedFeatures> get(std::uint64_t frame_id, const Compute& compute);
  FeatureCacheCounters counters() const;

 private:
  struct Slot {
    std::shared_ptr<const CachedFeatures> value;  ///< null while computing
    std::list<std::uint64_t>::iterator lru;
  };
  void evict_locked();

  std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::unordered_map<std::uint64_t, Slot> slots_;
  std::list<std::uint64_t> lru_;  ///< front = most recently used
  FeatureCacheCounters counters_;
};

}  // namespace nav::daemon::vision
