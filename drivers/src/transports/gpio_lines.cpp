// GPIO trigger output and strobe input on the Linux GPIO character device via libgpiod 1.6's
// C++ binding (see gpio_lines.h). libgpiod reports failures as std::system_error; they are
// converted to IoStatus here and never escape.

#include "nav/drivers/transports/gpio_lines.h"

#include <gpiod.hpp>
#include <system_error>

namespace nav::drivers {

struct GpioLines::Impl {
  gpiod::chip chip;
  gpiod::line trigger;
  gpiod::line strobe;
  bool has_trigger = false;
  bool has_strobe = false;
};

namespace {

IoStatus from_system_error(const std::system_error& e, const std::string& device,
                           const std::string& what) {
  return IoStatus::FromErrno(e.code().value(), device, what);
}

}  // namespace

IoStatus GpioOptions::validate() const {
  auto bad = [&](const std::string& what) {
    return IoStatus::Error(IoCode::kInvalidArgument, chip.empty() ? "gpio" : chip, what);
  };
  if (chip.empty()) return bad("options.chip is empty");
  if (trigger_line < -1 || strobe_line < -1)
    return bad("options line offsets must be >= 0 (or -1 for none)");
  if (trigger_line < 0 && strobe_line < 0)
    return bad("options: neither trigger_line nor strobe_line is set");
  if (trigger_line >= 0 && trigger_line == strobe_line)
    return bad("options: trigger_line equals strobe_line");
  if (consumer.empty()) return bad("options.consumer is empty");
  return IoStatus::Ok();
}

GpioLines::GpioLines(GpioOptions options)
    : options_(std::move(options)), options_status_(options_.validate()) {}

GpioLines::~GpioLines() { close(); }

IoStatus GpioLines::open() {
  if (!options_status_.ok()) return options_status_;
  close();
  auto impl = std::make_unique<Impl>();
  std::string step = "open chip";
  try {
    impl->chip.open(options_.chip, gpiod::chip::OPEN_BY_PATH);
    if (options_.trigger_line >= 0) {
      step = "request trigger line " + std::to_string(options_.trigger_line);
      impl->trigger = impl->chip.get_line(static_cast<unsigned>(options_.trigger_line));
      impl->trigger.request(
          {options_.consumer, gpiod::line_request::DIRECTION_OUTPUT,
           options_.trigger_active_low ? gpiod::line_request::FLAG_ACTIVE_LOW : std::bitset<32>{}},
          0);  // start inactive: never fire the camera by opening
      impl->has_trigger = true;
    }
    if (options_.strobe_line >= 0) {
      step = "request strobe line " + std::to_string(options_.strobe_line);
      impl->strobe = impl->chip.get_line(static_cast<unsigned>(options_.strobe_line));
      impl->strobe.request(
          {options_.consumer, gpiod::line_request::EVENT_BOTH_EDGES,
           options_.strobe_active_low ? gpiod::line_request::FLAG_ACTIVE_LOW : std::bitset<32>{}});
      impl->has_strobe = true;
    }
  } catch (const std::system_error& e) {
    return from_system_error(e, options_.chip, step);
  } catch (const std::exception& e) {  // libgpiod also throws std::out_of_range for bad offsets
    return IoStatus::Error(IoCode::kInvalidArgument, options_.chip, step + ": " + e.what());
  }
  impl_ = std::move(impl);
  return IoStatus::Ok();
}

void GpioLines::close() {
  if (!impl_) return;
  try {
    if (impl_->has_trigger) impl_->trigger.set_value(0);
    if (impl_->has_trigger) impl_->trigger.release();
    if (impl_->has_strobe) impl_->strobe.release();
  } catch (const std::exception&) {
    // The chip may be gone; the kernel releases the lines when the fd closes.
  }
  impl_.reset();
}

IoStatus GpioLines::set(bool active) {
  if (!impl_ || !impl_->has_trigger) {
    return IoStatus::Error(IoCode::kInvalidArgument, options_.chip, "set: no trigger line open");
  }
  try {
    impl_->trigger.set_value(active ? 1 : 0);
  } catch (const std::system_error& e) {
    return from_system_error(e, options_.chip, "set trigger line");
  }
  return IoStatus::Ok();
}

IoStatus GpioLines::wait_edge(EdgeEvent& event, std::chrono::milliseconds timeout) {
  if (!impl_ || !impl_->has_strobe) {
    return IoStatus::Error(IoCode::kInvalidArgument, options_.chip,
                           "wait_edge: no strobe line open");
  }
  try {
    if (!impl_->strobe.event_wait(timeout)) {
      return IoStatus::Error(IoCode::kTimeout, options_.chip, "no strobe edge within timeout");
    }
    const gpiod::line_event e = impl_->strobe.event_read();
    event.received = host_time_now();
    event.rising = e.event_type == gpiod::line_event::RISING_EDGE;
    event.kernel_time_us =
        std::chrono::duration_cast<std::chrono::microseconds>(e.timestamp).count();
  } catch (const std::system_error& e) {
    return from_system_error(e, options_.chip, "read strobe event");
  }
  return IoStatus::Ok();
}

}  // namespace nav::drivers
