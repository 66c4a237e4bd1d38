#pragma once
// Bounded multi-producer / single-consumer queue of measurements from driver threads to the
// filter thread, on moodycamel::ConcurrentQueue (lock-free, one sub-queue per producer token).
//
// Contract:
// * Capacity is exact: at most `capacity` measurements are queued at any time (an atomic count
//   reserved before enqueueing). A push into a full queue is dropped and counted on its producer;
//   producers never block and never wait for the consumer.
// * The constructor preallocates blocks for `capacity` items; a producer's sub-queue may allocate
//   a block while it grows to its high-water mark, not in steady state.
// * Order: FIFO per producer; no order across producers (time ordering is TimeOrderingBuffer's
//   job).
// * Threads: make_producer() at start-up (takes a mutex); each Producer is used by one thread;
//   try_pop() / pop_bulk() by the single consumer thread; counters readable from any thread.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "nav/daemon/queue/measurements.h"

namespace nav::daemon {

/// Per-producer counters (relaxed atomics inside; snapshot values here).
struct ProducerStats {
  std::string name;
  std::uint64_t pushed = 0;   ///< accepted into the queue
  std::uint64_t dropped = 0;  ///< rejected because the queue was full
};

class MeasurementQueue {
  struct Impl;
  struct Counters;

 public:
  /// `capacity` >= 1 (std::invalid_argument otherwise).
  explicit MeasurementQueue(std::size_t capacity);
  ~MeasurementQueue();
  MeasurementQueue(const MeasurementQueue&) = delete;
  MeasurementQueue& operator=(const MeasurementQueue&) = delete;

  /// A producer handle (one thread). Movable; must not outlive the queue.
  class Producer {
   public:
    Producer(Producer&&) noexcept;
    Producer& operator=(Producer&&) noexcept;
    ~Producer();
    /// True if queued; false if the queue was full (counted as a drop). Never blocks.
    bool push(const Measurement& m);
    std::size_t index() const { return index_; }

   private:
    friend class MeasurementQueue;
    struct Token;
    Producer(Impl* impl, Counters* counters, std::size_t index);
    Impl* impl_;
    Counters* counters_;  ///< stable: owned by the queue
    std::size_t index_;
    std::unique_ptr<Token> token_;
  };

  /// Registers a named producer (start-up only).
  Producer make_producer(std::string name);

  /// Consumer: next measurement if any.
  bool try_pop(Measurement& out);
  /// Consumer: appends up to `max` measurements to `out`; returns how many.
  std::size_t pop_bulk(std::vector<Measurement>& out, std::size_t max);

  std::size_t capacity() const;
  /// Reserved slots: queued measurements plus pushes in flight; never above capacity().
  std::size_t size() const;
  std::vector<ProducerStats> producer_stats() const;
  std::uint64_t total_dropped() const;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace nav::daemon
