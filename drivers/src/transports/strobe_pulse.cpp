// Strobe edge pairing (see gpio_lines.h), the pulse method of TriggerOutput and the in-memory
// LoopbackGpio.

#include <thread>

#include "nav/drivers/transports/gpio_lines.h"

namespace nav::drivers {

IoStatus TriggerOutput::pulse(std::chrono::microseconds width) {
  if (width.count() <= 0)
    return IoStatus::Error(IoCode::kInvalidArgument, "gpio", "pulse width must be > 0");
  if (IoStatus s = set(true); !s.ok()) return s;
  std::this_thread::sleep_for(width);
  return set(false);
}

std::optional<StrobePulse> StrobePulseDecoder::feed(const EdgeEvent& edge) {
  const int64_t t = edge.kernel_time_us;
  if (last_edge_us_ && t < *last_edge_us_) {
    ++stats_.out_of_order;
    open_since_us_.reset();  // cannot trust the pairing across a clock step
    return std::nullopt;
  }
  last_edge_us_ = t;
  if (edge.rising) {
    if (open_since_us_) ++stats_.orphan_edges;  // the falling edge of the previous pulse was lost
    open_since_us_ = t;
    return std::nullopt;
  }
  if (!open_since_us_) {
    ++stats_.orphan_edges;
    return std::nullopt;
  }
  const StrobePulse pulse{*open_since_us_, t};
  open_since_us_.reset();
  if (pulse.width_us() > max_width_us_) {
    ++stats_.too_long;
    return std::nullopt;
  }
  ++stats_.pulses;
  return pulse;
}

IoStatus LoopbackGpio::set(bool active) {
  {
    std::lock_guard lock(mutex_);
    if (active == level_) return IoStatus::Ok();  // no level change, no edge
    level_ = active;
    const HostTime now = host_time_now();
    events_.push_back(EdgeEvent{active, now.monotonic_us, now});
  }
  ready_.notify_one();
  return IoStatus::Ok();
}

void LoopbackGpio::inject(const EdgeEvent& event) {
  {
    std::lock_guard lock(mutex_);
    events_.push_back(event);
  }
  ready_.notify_one();
}

IoStatus LoopbackGpio::wait_edge(EdgeEvent& event, std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  if (!ready_.wait_for(lock, timeout, [this] { return !events_.empty(); })) {
    return IoStatus::Error(IoCode::kTimeout, "gpio-loopback", "no edge within timeout");
  }
  event = events_.front();
  events_.pop_front();
  return IoStatus::Ok();
}

}  // namespace nav::drivers
