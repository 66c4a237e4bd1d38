#pragma once
// GPIO lines for camera triggering and strobe time stamping (Linux GPIO character device
// through libgpiod 1.6, https://git.kernel.org/pub/scm/libs/libgpiod/libgpiod.git): an output
// line that fires the camera (hardware trigger, GigeOptions::trigger_mode = kHardware) and an
// input line that sees the camera's strobe/exposure-active output, with kernel edge time stamps
// (CLOCK_MONOTONIC on Linux >= 5.7). Image times in navd come from the strobe: the exposure
// mid-point of each StrobePulse.
//
// TriggerOutput and EdgeInput are the interfaces drivers use; GpioLines implements both on a
// gpiochip, LoopbackGpio in memory (the trigger output wired to the strobe input) for tests and
// replay. StrobePulseDecoder pairs edges into pulses (pure).
//
// Threading: one driver thread owns a GpioLines; wait_edge() blocks for at most its timeout.
// LoopbackGpio is thread-safe (set/pulse from one thread, wait_edge from another).

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "nav/drivers/time/timestamps.h"
#include "nav/drivers/transports/io_status.h"

namespace nav::drivers {

struct EdgeEvent {
  bool rising = false;         ///< logical level went active (after active-low inversion)
  int64_t kernel_time_us = 0;  ///< kernel time stamp of the edge (CLOCK_MONOTONIC, µs)
  HostTime received;           ///< host clocks when the event was read
};

class TriggerOutput {
 public:
  virtual ~TriggerOutput() = default;
  /// Drives the line to its active (true) or inactive level.
  virtual IoStatus set(bool active) = 0;
  /// Active for `width`, then inactive (sleeps on the calling thread for `width`).
  IoStatus pulse(std::chrono::microseconds width);
};

class EdgeInput {
 public:
  virtual ~EdgeInput() = default;
  /// Next edge, waiting at most `timeout`; kTimeout when none arrived.
  virtual IoStatus wait_edge(EdgeEvent& event, std::chrono::milliseconds timeout) = 0;
};

struct GpioOptions {
  std::string chip = "/dev/gpiochip0";  ///< character device of the GPIO controller
  int trigger_line = -1;                ///< line offset of the trigger output; -1: none
  int strobe_line = -1;                 ///< line offset of the strobe input; -1: none
  bool trigger_active_low = false;
  bool strobe_active_low = false;
  std::string consumer = "navd";  ///< label shown by gpioinfo

  IoStatus validate() const;
};

class GpioLines final : public TriggerOutput, public EdgeInput {
 public:
  explicit GpioLines(GpioOptions options);
  ~GpioLines() override;
  GpioLines(const GpioLines&) = delete;
  GpioLines& operator=(const GpioLines&) = delete;

  /// Opens the chip and requests the configured lines (trigger driven inactive at once).
  /// kDisconnected when the chip is missing, kBusy when a line is taken by another consumer.
  IoStatus open();
  void close();

  IoStatus set(bool active) override;
  IoStatus wait_edge(EdgeEvent& event, std::chrono::milliseconds timeout) override;

 private:
  struct Impl;  // keeps gpiod.hpp out of this header
  GpioOptions options_;
  IoStatus options_status_;
  std::unique_ptr<Impl> impl_;
};

/// In-memory trigger output wired to an edge input (what a camera strobe would echo): each
/// level change of set() becomes an EdgeEvent stamped with the host monotonic clock.
class LoopbackGpio final : public TriggerOutput, public EdgeInput {
 public:
  IoStatus set(bool active) override;
  IoStatus wait_edge(EdgeEvent& event, std::chrono::milliseconds timeout) override;
  /// Queues an edge with a chosen time (replay of a recorded strobe log).
  void inject(const EdgeEvent& event);

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<EdgeEvent> events_;
  bool level_ = false;
};

/// One active period of the strobe (camera exposing).
struct StrobePulse {
  int64_t start_us = 0;  ///< rising (active) edge, kernel monotonic µs
  int64_t end_us = 0;    ///< falling edge
  int64_t mid_us() const { return start_us + (end_us - start_us) / 2; }
  int64_t width_us() const { return end_us - start_us; }
};

/// Pairs strobe edges into pulses. A rising edge followed by another rising edge (a falling
/// edge was missed), a falling edge without a rising one, edges going back in time, and pulses
/// longer than `max_width_us` (a stuck line) are counted and dropped, never paired wrongly.
class StrobePulseDecoder {
 public:
  struct Stats {
    uint64_t pulses = 0;
    uint64_t orphan_edges = 0;  ///< unpaired rising/falling edges
    uint64_t too_long = 0;      ///< pulses wider than max_width_us
    uint64_t out_of_order = 0;  ///< edges older than the previous one
  };

  explicit StrobePulseDecoder(int64_t max_width_us = 1'000'000) : max_width_us_(max_width_us) {}
  /// A complete pulse when `edge` closes one.
  std::optional<StrobePulse> feed(const EdgeEvent& edge);
  const Stats& stats() const { return stats_; }

 private:
  int64_t max_width_us_;
  std::optional<int64_t> open_since_us_;
  std::optional<int64_t> last_edge_us_;
  Stats stats_;
};

}  // namespace nav::drivers
