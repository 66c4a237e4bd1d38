#pragma once
// Releases measurements to the filter in time-of-validity order. Sensors deliver with different
// latencies (a DVL ensemble is valid well before it is parsed; a camera frame later still), so
// the filter thread holds each measurement until it is at least `latency_window_us` older than
// the newest time of validity seen, then releases the oldest first.
//
// Policy (counted, never silent):
// * Release: a held measurement m is ready when validity(m) <= newest_validity - window.
//   Equal times are released in arrival order. flush() releases everything (shutdown).
// * Late arrival: validity(m) < validity of the last released measurement -> dropped and counted
//   in `dropped_late` (the filter has already moved past that time; re-ordering it in would
//   need a rewind). Equal to the last released time is accepted.
// * Full: at `capacity` held measurements the incoming one is dropped and counted in
//   `dropped_full`. Capacity must exceed (total measurement rate x window) with margin.
// * No allocation after construction (storage reserved for `capacity`); single thread (the
//   filter thread) only.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "nav/daemon/queue/measurements.h"

namespace nav::daemon {

struct TimeOrderingOptions {
  std::int64_t latency_window_us = 200'000;  ///< >= 0 (from filter.latency_window_ms)
  std::size_t capacity = 4096;               ///< >= 1 held measurements

  /// Throws std::invalid_argument naming the field.
  void validate() const;
};

struct TimeOrderingStats {
  std::uint64_t accepted = 0;
  std::uint64_t released = 0;
  std::uint64_t dropped_late = 0;
  std::uint64_t dropped_full = 0;
};

class TimeOrderingBuffer {
 public:
  enum class InsertResult { kAccepted, kDroppedLate, kDroppedFull };

  explicit TimeOrderingBuffer(const TimeOrderingOptions& options = {});

  InsertResult insert(const Measurement& m);
  /// The oldest held measurement if it is ready (see policy), removing it.
  std::optional<Measurement> pop_ready();
  /// The oldest held measurement regardless of the window (shutdown / end of a log).
  std::optional<Measurement> pop_any();

  std::size_t size() const { return heap_.size(); }
  const TimeOrderingStats& stats() const { return stats_; }
  /// Newest time of validity inserted so far (nullopt before the first).
  std::optional<std::int64_t> newest_validity_us() const { return newest_us_; }
  /// Time of validity of the last released measurement (nullopt before the first).
  std::optional<std::int64_t> last_released_us() const { return last_released_us_; }

 private:
  struct Entry {
    std::int64_t validity_us;
    std::uint64_t sequence;  ///< arrival order: ties released first-in first-out
    Measurement measurement;
  };
  static bool later(const Entry& a, const Entry& b);  ///< heap order: min (time, sequence) on top
  Measurement pop_top();

  TimeOrderingOptions options_;
  std::vector<Entry> heap_;
  std::uint64_t next_sequence_ = 0;
  std::optional<std::int64_t> newest_us_;
  std::optional<std::int64_t> last_released_us_;
  TimeOrderingStats stats_;
};

}  // namespace nav::daemon
