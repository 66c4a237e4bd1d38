// Device source loops for serial and CAN sensors (nav/daemon/sources/device_source.h).
#include "nav/daemon/sources/device_source.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/raw_bytes_t.hpp>
#include <thread>
#include <vector>

#include "nav/daemon/log/dive_log.h"

namespace nav::daemon {
namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kRelaxed = std::memory_order_relaxed;

/// Sleeps up to `duration` in short steps, returning early on stop.
void sleep_unless_stopped(std::chrono::milliseconds duration, const std::atomic<bool>& stop) {
  const auto end = Clock::now() + duration;
  while (!stop.load() && Clock::now() < end) {
    std::this_thread::sleep_for(
        std::min<Clock::duration>(end - Clock::now(), std::chrono::milliseconds(20)));
  }
}

/// Decoded measurements into the queue (drops counted) and the decoder's counters into health.
void publish_decoded(std::vector<Measurement>& measurements, std::int64_t host_monotonic_us,
                     std::uint64_t messages_before, DeviceLoopContext& c) {
  for (const Measurement& m : measurements) {
    if (!c.producer.push(m)) c.health.queue_drops.fetch_add(1, kRelaxed);
  }
  measurements.clear();
  const SensorDecoderCounters counters = c.decoder.counters();
  c.health.store(counters);
  if (counters.messages != messages_before) {
    c.health.last_message_monotonic_us.store(host_monotonic_us, kRelaxed);
  }
}

/// Connection bookkeeping shared by the loops.
class Connection {
 public:
  explicit Connection(SensorHealth& health) : health_(health) {}
  void delivering(const std::string& device) {
    if (health_.connected.load(kRelaxed)) return;
    health_.connected.store(true, kRelaxed);
    if (ever_connected_) {
      health_.reconnects.fetch_add(1, kRelaxed);
      spdlog::info("sensor {}: {} is back", health_.name, device);
    }
    ever_connected_ = true;
  }
  void lost(const drivers::IoStatus& status) {
    if (health_.connected.exchange(false, kRelaxed)) {
      health_.disconnects.fetch_add(1, kRelaxed);
      spdlog::warn("sensor {}: {}", health_.name, status.message());
    } else if (!warned_) {
      spdlog::warn("sensor {}: {}", health_.name, status.message());
    }
    warned_ = true;
  }

 private:
  SensorHealth& health_;
  bool ever_connected_ = false;
  bool warned_ = false;
};

}  // namespace

bool LcmRawPublisher::publish_raw(const std::string& sensor_name, std::int64_t host_realtime_us,
                                  std::int64_t host_monotonic_us,
                                  std::span<const std::uint8_t> bytes) {
  if (lcm_ == nullptr) return false;
  navlcm::raw_bytes_t msg;
  msg.utime = host_realtime_us;
  msg.host_monotonic_us = host_monotonic_us;
  msg.device = sensor_name;
  msg.num_bytes = static_cast<std::int32_t>(bytes.size());
  msg.data.assign(bytes.begin(), bytes.end());
  const std::string channel = raw_channel(sensor_name);
  std::lock_guard lock(mutex_);
  const bool ok = lcm_->publish(channel, &msg) == 0;
  (ok ? published_ : failures_).fetch_add(1);
  return ok;
}

bool LcmRawPublisher::publish_image(const navlcm::image_metadata_t& image) {
  if (lcm_ == nullptr) return false;
  std::lock_guard lock(mutex_);
  const bool ok = lcm_->publish(std::string(kImageChannel), &image) == 0;
  (ok ? published_ : failures_).fetch_add(1);
  return ok;
}

void run_byte_device(drivers::ByteStream& stream, DeviceLoopContext& c) {
  c.health.active.store(true);
  Connection connection(c.health);
  std::vector<std::uint8_t> buffer(std::max<std::size_t>(c.options.read_buffer_bytes, 1));
  std::vector<Measurement> measurements;
  while (!c.stop.load()) {
    const auto started = Clock::now();
    const drivers::ReadResult r = stream.read(buffer, c.options.read_timeout);
    if (r.status.ok()) {
      connection.delivering(stream.name());
      const std::span<const std::uint8_t> bytes(buffer.data(), r.bytes);
      if (c.raw != nullptr) {
        c.raw->publish_raw(c.decoder.sensor_name(), r.received.realtime_us, r.received.monotonic_us,
                           bytes);
      }
      const std::uint64_t before = c.decoder.counters().messages;
      c.decoder.feed(bytes, r.received.realtime_us, r.received.monotonic_us, measurements);
      publish_decoded(measurements, r.received.monotonic_us, before, c);
      continue;
    }
    if (r.status.code() == drivers::IoCode::kTimeout) continue;
    connection.lost(r.status);
    const auto spent =
        std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - started);
    if (spent < c.options.read_timeout)
      sleep_unless_stopped(c.options.read_timeout - spent, c.stop);
  }
  c.health.connected.store(false);
}

void run_can_device(const CanBusOpener& open, const std::string& interface, DeviceLoopContext& c) {
  c.health.active.store(true);
  Connection connection(c.health);
  std::unique_ptr<drivers::CanBus> bus;
  std::chrono::milliseconds backoff{0};
  std::vector<Measurement> measurements;
  drivers::CanFrame frame;
  while (!c.stop.load()) {
    if (!bus) {
      drivers::IoStatus status;
      bus = open(status);
      if (!bus) {
        c.health.open_failures.fetch_add(1, kRelaxed);
        connection.lost(status);
        backoff = std::clamp(backoff * 2, c.options.reconnect_initial, c.options.reconnect_max);
        sleep_unless_stopped(backoff, c.stop);
        continue;
      }
      backoff = std::chrono::milliseconds{0};
    }
    const drivers::IoStatus status = bus->receive(frame, c.options.read_timeout);
    if (status.code() == drivers::IoCode::kTimeout) continue;
    if (!status.ok()) {
      connection.lost(status);
      bus.reset();  // reopened at the top of the loop
      continue;
    }
    connection.delivering(bus->name());
    const std::int64_t mono = frame.received.monotonic_us;
    if (c.raw != nullptr) {
      const std::string line = can_frame_log_line(frame, interface);
      c.raw->publish_raw(c.decoder.sensor_name(), frame.received.realtime_us, mono,
                         {reinterpret_cast<const std::uint8_t*>(line.data()), line.size()});
    }
    const std::uint64_t before = c.decoder.counters().messages;
    c.decoder.feed_frame(frame, measurements);
    publish_decoded(measurements, mono, before, c);
  }
  c.health.connected.store(false);
}

}  // namespace nav::daemon
