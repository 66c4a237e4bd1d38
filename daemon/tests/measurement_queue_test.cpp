// Bounded MPSC measurement queue: FIFO per producer, exact capacity, drops counted per producer,
// and a multi-threaded run where every measurement is either delivered once or counted as dropped.
#include "nav/daemon/queue/measurement_queue.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

namespace nav::daemon {
namespace {

Measurement depth(std::int64_t t_us, std::uint16_t sensor = 0, double d = 0.0) {
  Depth m;
  m.time.validity_us = t_us;
  m.time.sensor_index = sensor;
  m.depth_m = d;
  return m;
}

TEST(MeasurementQueue, FifoForOneProducer) {
  MeasurementQueue q(8);
  auto p = q.make_producer("dvl");
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(p.push(depth(i, 0, 0.5 * i)));
  EXPECT_EQ(q.size(), 5u);
  Measurement m;
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(q.try_pop(m));
    EXPECT_EQ(validity_us(m), i);
    EXPECT_DOUBLE_EQ(std::get<Depth>(m).depth_m, 0.5 * i);
  }
  EXPECT_FALSE(q.try_pop(m));
}

TEST(MeasurementQueue, OverflowIsDroppedAndCountedPerProducer) {
  MeasurementQueue q(4);
  auto a = q.make_producer("a");
  auto b = q.make_producer("b");
  EXPECT_TRUE(a.push(depth(1)));
  EXPECT_TRUE(a.push(depth(2)));
  EXPECT_TRUE(b.push(depth(3)));
  EXPECT_TRUE(b.push(depth(4)));
  EXPECT_FALSE(a.push(depth(5)));
  EXPECT_FALSE(b.push(depth(6)));
  EXPECT_FALSE(b.push(depth(7)));
  EXPECT_EQ(q.size(), 4u);
  const auto stats = q.producer_stats();
  ASSERT_EQ(stats.size(), 2u);
  EXPECT_EQ(stats[0].name, "a");
  EXPECT_EQ(stats[0].pushed, 2u);
  EXPECT_EQ(stats[0].dropped, 1u);
  EXPECT_EQ(stats[1].pushed, 2u);
  EXPECT_EQ(stats[1].dropped, 2u);
  EXPECT_EQ(q.total_dropped(), 3u);
  // Space frees up after the consumer pops.
  std::vector<Measurement> out;
  EXPECT_EQ(q.pop_bulk(out, 1), 1u);
  EXPECT_TRUE(a.push(depth(8)));
  EXPECT_FALSE(a.push(depth(9)));
  EXPECT_EQ(q.pop_bulk(out, 100), 4u);
  EXPECT_EQ(out.size(), 5u);
  EXPECT_EQ(q.size(), 0u);
}

TEST(MeasurementQueue, ZeroCapacityIsRejected) {
  EXPECT_THROW(MeasurementQueue(0), std::invalid_argument);
}

TEST(MeasurementQueue, MultiThreadedProducersDeliverOrCountEverything) {
  constexpr int kProducers = 4;
  constexpr int kPerProducer = 20000;
  MeasurementQueue q(256);
  std::vector<MeasurementQueue::Producer> producers;
  for (int i = 0; i < kProducers; ++i) {
    std::string name = "p";  // (not "p" + to_string: GCC 12 -O3 -Wrestrict false positive)
    name += std::to_string(i);
    producers.push_back(q.make_producer(name));
  }

  std::atomic<int> done{0};
  std::vector<std::thread> threads;
  for (int i = 0; i < kProducers; ++i) {
    threads.emplace_back([&, i] {
      for (int k = 0; k < kPerProducer; ++k) {
        producers[i].push(depth(k, static_cast<std::uint16_t>(i)));
      }
      done.fetch_add(1);
    });
  }
  // Single consumer: per-producer FIFO (validity strictly increasing per sensor), no duplicates,
  // never more than capacity queued.
  std::vector<std::int64_t> last(kProducers, -1);
  std::vector<std::uint64_t> received(kProducers, 0);
  std::vector<Measurement> batch;
  for (;;) {
    const bool finished = done.load() == kProducers;
    EXPECT_LE(q.size(), q.capacity());
    batch.clear();
    q.pop_bulk(batch, 64);
    for (const Measurement& m : batch) {
      const MeasurementTime& t = time_of(m);
      ASSERT_LT(t.sensor_index, kProducers);
      EXPECT_GT(t.validity_us, last[t.sensor_index]);
      last[t.sensor_index] = t.validity_us;
      ++received[t.sensor_index];
    }
    if (finished && batch.empty()) break;
    if (batch.empty()) std::this_thread::yield();
  }
  for (auto& t : threads) t.join();

  const auto stats = q.producer_stats();
  std::uint64_t total_dropped = 0;
  for (int i = 0; i < kProducers; ++i) {
    EXPECT_EQ(stats[i].pushed, received[i]) << "producer " << i;
    EXPECT_EQ(stats[i].pushed + stats[i].dropped, static_cast<std::uint64_t>(kPerProducer));
    total_dropped += stats[i].dropped;
  }
  EXPECT_EQ(q.total_dropped(), total_dropped);
}

TEST(MeasurementQueue, SlowConsumerCausesCountedDropsNotBlocking) {
  MeasurementQueue q(16);
  auto p = q.make_producer("fast");
  std::thread producer([&] {
    for (int k = 0; k < 1000; ++k) p.push(depth(k));
  });
  producer.join();  // completes with nobody consuming: producers never block
  EXPECT_EQ(q.size(), 16u);
  EXPECT_EQ(q.producer_stats()[0].dropped, 1000u - 16u);
}

}  // namespace
}  // namespace nav::daemon
