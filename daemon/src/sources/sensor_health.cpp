// Per-sensor health board (nav/daemon/sources/sensor_health.h).
#include "nav/daemon/sources/sensor_health.h"

namespace nav::daemon {

void SensorHealth::store(const SensorDecoderCounters& c) {
  constexpr auto kRelaxed = std::memory_order_relaxed;
  bytes.store(c.bytes, kRelaxed);
  messages.store(c.messages, kRelaxed);
  measurements.store(c.measurements, kRelaxed);
  decode_errors.store(c.decode_errors, kRelaxed);
  dropped_bytes.store(c.dropped_bytes, kRelaxed);
}

SensorHealthBoard::SensorHealthBoard(const NavdConfig& config) {
  for (const SensorConfig& s : config.sensors) {
    sensors_.push_back(std::make_unique<SensorHealth>(s.name));
  }
  previous_messages_.assign(sensors_.size(), 0);
}

std::vector<navlcm::sensor_health_t> SensorHealthBoard::snapshot(std::int64_t now_us) {
  constexpr auto kRelaxed = std::memory_order_relaxed;
  std::vector<navlcm::sensor_health_t> out;
  const double elapsed_s = previous_us_ >= 0 ? double(now_us - previous_us_) * 1e-6 : 0.0;
  for (std::size_t i = 0; i < sensors_.size(); ++i) {
    const SensorHealth& h = *sensors_[i];
    const std::uint64_t messages = h.messages.load(kRelaxed);
    const std::uint64_t new_messages = messages - previous_messages_[i];
    previous_messages_[i] = messages;
    if (!h.active.load(kRelaxed)) continue;
    navlcm::sensor_health_t m{};
    m.name = h.name;
    m.rate_hz = elapsed_s > 0.0 ? double(new_messages) / elapsed_s : 0.0;
    m.records = static_cast<std::int64_t>(messages);
    m.decode_errors = static_cast<std::int64_t>(h.decode_errors.load(kRelaxed));
    m.dropped_bytes = static_cast<std::int64_t>(h.dropped_bytes.load(kRelaxed));
    m.queue_drops = static_cast<std::int64_t>(h.queue_drops.load(kRelaxed));
    m.late_measurements = 0;  // counted by the filter's time ordering, not per device
    m.bytes = static_cast<std::int64_t>(h.bytes.load(kRelaxed));
    m.measurements = static_cast<std::int64_t>(h.measurements.load(kRelaxed));
    m.reconnects = static_cast<std::int64_t>(h.reconnects.load(kRelaxed));
    const std::int64_t last = h.last_message_monotonic_us.load(kRelaxed);
    m.last_message_age_s = last >= 0 ? double(now_us - last) * 1e-6 : -1.0;
    m.connected = h.connected.load(kRelaxed);
    m.num_components = 0;
    out.push_back(std::move(m));
  }
  previous_us_ = now_us;
  return out;
}

}  // namespace nav::daemon
