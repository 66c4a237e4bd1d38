#pragma once
// FilterWorker: a filter fed on its own thread (the replay's dead-reckoning baseline).
//
// The replay's filter thread hands every time-ordered measurement to push(); the worker thread
// applies them to its filter in exactly that order, so the result is the same as if it were
// fed inline (deterministic, independent of thread timing). Measurements travel in
// batches (one lock per batch, not per measurement). The filter must not be touched by anyone
// else until finish() has returned. On the first failing measurement the worker stops
// applying and records the error (failed() turns true; the caller stops feeding).

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "nav/core/status.h"
#include "nav/daemon/queue/measurements.h"

namespace nav::daemon {

class FilterWorker {
 public:
  /// Applies one measurement to the filter (an error stops the worker).
  using Apply = std::function<core::Status(const Measurement&)>;
  /// Starts the thread. `name` prefixes error messages (e.g. "dead-reckoning filter").
  FilterWorker(Apply apply, std::string name, std::size_t batch_size = 512);
  ~FilterWorker();  ///< joins (measurements not yet applied are dropped)
  FilterWorker(const FilterWorker&) = delete;
  FilterWorker& operator=(const FilterWorker&) = delete;

  /// Queues one measurement (applied after every earlier one). Hands a full batch to the thread.
  void push(const Measurement& m);
  /// Applies everything queued, joins the thread. Returns the error ("" if none):
  /// "<name> at t = <us> us: <status>".
  std::string finish();
  /// True once a measurement failed (cheap; the message comes from finish()).
  bool failed() const;

 private:
  void run();
  void hand_over();  // moves pending_ to the shared queue

  Apply apply_;
  std::string name_;
  std::size_t batch_size_;
  std::vector<Measurement> pending_;  // producer side, not shared
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<std::vector<Measurement>> batches_;  // shared, guarded by mutex_
  std::vector<std::vector<Measurement>> spare_;    // emptied batches returned for reuse
  bool closing_ = false;
  bool failed_ = false;
  std::string error_;
  std::thread thread_;
};

}  // namespace nav::daemon
