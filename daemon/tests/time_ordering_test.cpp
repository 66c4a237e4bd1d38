// Time-of-validity ordering: release after the latency window, order by validity (ties in
// arrival order), late arrivals and overflow dropped and counted, flush at shutdown.
#include "nav/daemon/queue/time_ordering.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <stdexcept>
#include <vector>

namespace nav::daemon {
namespace {

Measurement alt(std::int64_t t_us, double a = 0.0) {
  Altitude m;
  m.time.validity_us = t_us;
  m.altitude_m = a;
  return m;
}

std::vector<std::int64_t> drain_ready(TimeOrderingBuffer& b) {
  std::vector<std::int64_t> out;
  while (auto m = b.pop_ready()) out.push_back(validity_us(*m));
  return out;
}

TEST(TimeOrdering, ReleasesOnlyOutsideTheWindowInOrder) {
  TimeOrderingBuffer b({.latency_window_us = 100, .capacity = 16});
  EXPECT_FALSE(b.pop_ready().has_value());
  b.insert(alt(50));
  b.insert(alt(10));
  b.insert(alt(30));
  EXPECT_TRUE(drain_ready(b).empty());  // newest 50: nothing <= -50
  b.insert(alt(130));                   // newest 130: ready <= 30
  EXPECT_EQ(drain_ready(b), (std::vector<std::int64_t>{10, 30}));
  b.insert(alt(150));  // ready <= 50
  EXPECT_EQ(drain_ready(b), (std::vector<std::int64_t>{50}));
  EXPECT_EQ(b.size(), 2u);
  EXPECT_EQ(*b.newest_validity_us(), 150);
  EXPECT_EQ(*b.last_released_us(), 50);
}

TEST(TimeOrdering, LateArrivalsAreDroppedAndCounted) {
  TimeOrderingBuffer b({.latency_window_us = 10, .capacity = 16});
  b.insert(alt(100));
  b.insert(alt(200));
  EXPECT_EQ(drain_ready(b), (std::vector<std::int64_t>{100}));
  EXPECT_EQ(b.insert(alt(99)), TimeOrderingBuffer::InsertResult::kDroppedLate);
  EXPECT_EQ(b.insert(alt(100)), TimeOrderingBuffer::InsertResult::kAccepted);  // equal: in order
  EXPECT_EQ(b.insert(alt(150)), TimeOrderingBuffer::InsertResult::kAccepted);  // late-ish, in order
  EXPECT_EQ(drain_ready(b), (std::vector<std::int64_t>{100, 150}));
  EXPECT_EQ(b.stats().dropped_late, 1u);
  EXPECT_EQ(b.stats().accepted, 4u);
  EXPECT_EQ(b.stats().released, 3u);
}

TEST(TimeOrdering, EqualTimesReleaseInArrivalOrder) {
  TimeOrderingBuffer b({.latency_window_us = 0, .capacity = 16});
  b.insert(alt(5, 1.0));
  b.insert(alt(5, 2.0));
  b.insert(alt(5, 3.0));
  for (double expected : {1.0, 2.0, 3.0}) {
    auto m = b.pop_ready();
    ASSERT_TRUE(m.has_value());
    EXPECT_DOUBLE_EQ(std::get<Altitude>(*m).altitude_m, expected);
  }
}

TEST(TimeOrdering, ZeroWindowReleasesImmediately) {
  TimeOrderingBuffer b({.latency_window_us = 0, .capacity = 4});
  b.insert(alt(7));
  EXPECT_EQ(drain_ready(b), (std::vector<std::int64_t>{7}));
}

TEST(TimeOrdering, FullBufferDropsIncomingAndCounts) {
  TimeOrderingBuffer b({.latency_window_us = 1000, .capacity = 3});
  for (int t : {1, 2, 3}) EXPECT_EQ(b.insert(alt(t)), TimeOrderingBuffer::InsertResult::kAccepted);
  EXPECT_EQ(b.insert(alt(4)), TimeOrderingBuffer::InsertResult::kDroppedFull);
  EXPECT_EQ(b.size(), 3u);
  EXPECT_EQ(b.stats().dropped_full, 1u);
  std::vector<std::int64_t> all;
  while (auto m = b.pop_any()) all.push_back(validity_us(*m));
  EXPECT_EQ(all, (std::vector<std::int64_t>{1, 2, 3}));
}

TEST(TimeOrdering, InvalidOptionsAreRejected) {
  EXPECT_THROW(TimeOrderingBuffer({.latency_window_us = -1, .capacity = 1}), std::invalid_argument);
  EXPECT_THROW(TimeOrderingBuffer({.latency_window_us = 1, .capacity = 0}), std::invalid_argument);
}

// Sensors with random delivery latency below the window: output is the sorted input, nothing
// dropped. With latencies above the window some become late: output stays sorted and every
// input is either released or counted.
TEST(TimeOrdering, RandomLatenciesWithinWindowGiveSortedOutput) {
  for (const std::int64_t max_latency_us : {50'000, 400'000}) {
    std::mt19937 rng(7);
    std::uniform_int_distribution<std::int64_t> latency(0, max_latency_us);
    struct Arrival {
      std::int64_t arrival_us, validity_us;
    };
    std::vector<Arrival> arrivals;
    for (std::int64_t t = 0; t < 2'000'000; t += 1'000) arrivals.push_back({t + latency(rng), t});
    std::sort(arrivals.begin(), arrivals.end(),
              [](const Arrival& a, const Arrival& b) { return a.arrival_us < b.arrival_us; });

    TimeOrderingBuffer b({.latency_window_us = 100'000, .capacity = 4096});
    std::vector<std::int64_t> out;
    for (const Arrival& a : arrivals) {
      b.insert(alt(a.validity_us));
      while (auto m = b.pop_ready()) out.push_back(validity_us(*m));
    }
    while (auto m = b.pop_any()) out.push_back(validity_us(*m));
    EXPECT_TRUE(std::is_sorted(out.begin(), out.end()));
    EXPECT_EQ(out.size() + b.stats().dropped_late, arrivals.size());
    if (max_latency_us < 100'000) {
      EXPECT_EQ(b.stats().dropped_late, 0u);
    } else {
      EXPECT_GT(b.stats().dropped_late, 0u);
    }
  }
}

}  // namespace
}  // namespace nav::daemon
