// Bounded MPSC measurement queue on moodycamel::ConcurrentQueue: see measurement_queue.h.
#include "nav/daemon/queue/measurement_queue.h"

#include <concurrentqueue.h>

#include <atomic>
#include <deque>
#include <mutex>
#include <stdexcept>

namespace nav::daemon {

struct MeasurementQueue::Counters {
  std::string name;
  std::atomic<std::uint64_t> pushed{0};
  std::atomic<std::uint64_t> dropped{0};
};

struct MeasurementQueue::Impl {
  explicit Impl(std::size_t cap) : capacity(cap), queue(cap) {}

  const std::size_t capacity;
  moodycamel::ConcurrentQueue<Measurement> queue;
  std::atomic<std::size_t> count{0};  ///< reserved slots (queued + being enqueued)
  mutable std::mutex producers_mutex;
  std::deque<Counters> producers;  ///< deque: stable addresses while producers are added
};

struct MeasurementQueue::Producer::Token {
  explicit Token(moodycamel::ConcurrentQueue<Measurement>& q) : token(q) {}
  moodycamel::ProducerToken token;
};

MeasurementQueue::MeasurementQueue(std::size_t capacity) {
  if (capacity == 0) throw std::invalid_argument("MeasurementQueue: capacity must be >= 1");
  impl_ = std::make_unique<Impl>(capacity);
}

MeasurementQueue::~MeasurementQueue() = default;

MeasurementQueue::Producer::Producer(Impl* impl, Counters* counters, std::size_t index)
    : impl_(impl),
      counters_(counters),
      index_(index),
      token_(std::make_unique<Token>(impl->queue)) {}
MeasurementQueue::Producer::Producer(Producer&&) noexcept = default;
MeasurementQueue::Producer& MeasurementQueue::Producer::operator=(Producer&&) noexcept = default;
MeasurementQueue::Producer::~Producer() = default;

bool MeasurementQueue::Producer::push(const Measurement& m) {
  Counters& counters = *counters_;
  // Reserve a slot first (compare-exchange, so the count itself never exceeds capacity).
  std::size_t reserved = impl_->count.load(std::memory_order_acquire);
  do {
    if (reserved >= impl_->capacity) {
      counters.dropped.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
  } while (!impl_->count.compare_exchange_weak(reserved, reserved + 1, std::memory_order_acq_rel,
                                               std::memory_order_acquire));
  if (!impl_->queue.enqueue(token_->token, m)) {  // only on allocation failure
    impl_->count.fetch_sub(1, std::memory_order_acq_rel);
    counters.dropped.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  counters.pushed.fetch_add(1, std::memory_order_relaxed);
  return true;
}

MeasurementQueue::Producer MeasurementQueue::make_producer(std::string name) {
  std::lock_guard lock(impl_->producers_mutex);
  Counters& counters = impl_->producers.emplace_back();
  counters.name = std::move(name);
  return Producer(impl_.get(), &counters, impl_->producers.size() - 1);
}

bool MeasurementQueue::try_pop(Measurement& out) {
  if (!impl_->queue.try_dequeue(out)) return false;
  impl_->count.fetch_sub(1, std::memory_order_acq_rel);
  return true;
}

std::size_t MeasurementQueue::pop_bulk(std::vector<Measurement>& out, std::size_t max) {
  std::size_t n = 0;
  Measurement m;
  while (n < max && try_pop(m)) {
    out.push_back(m);
    ++n;
  }
  return n;
}

std::size_t MeasurementQueue::capacity() const { return impl_->capacity; }

std::size_t MeasurementQueue::size() const { return impl_->count.load(std::memory_order_acquire); }

std::vector<ProducerStats> MeasurementQueue::producer_stats() const {
  std::lock_guard lock(impl_->producers_mutex);
  std::vector<ProducerStats> out;
  for (const Counters& c : impl_->producers) {
    out.push_back({c.name, c.pushed.load(std::memory_order_relaxed),
                   c.dropped.load(std::memory_order_relaxed)});
  }
  return out;
}

std::uint64_t MeasurementQueue::total_dropped() const {
  std::uint64_t total = 0;
  for (const ProducerStats& s : producer_stats()) total += s.dropped;
  return total;
}

}  // namespace nav::daemon
