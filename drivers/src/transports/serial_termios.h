#pragma once
// Internal: SerialOptions -> termios mapping shared by SerialPort and its tests' expectations.

#include <termios.h>

#include <optional>

#include "nav/drivers/transports/serial_port.h"

namespace nav::drivers {

/// termios speed constant for a baud rate, or nullopt when it is not a standard rate.
std::optional<speed_t> baud_to_speed(int baud);
/// Raw mode plus the framing, parity, flow control and speed of `options` (already validated).
void apply_serial_options(const SerialOptions& options, termios& tio);

}  // namespace nav::drivers
