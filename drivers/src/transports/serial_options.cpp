// SerialOptions validation and the mapping of options onto a termios structure (termios(3),
// POSIX.1-2017 "General Terminal Interface"; Linux adds the B57600 ... B4000000 rates).

#include <termios.h>

#include <array>
#include <utility>

#include "nav/drivers/transports/serial_port.h"
#include "serial_termios.h"

namespace nav::drivers {
namespace {

constexpr std::array<std::pair<int, speed_t>, 31> kBaudRates{{
    {50, B50},
    {75, B75},
    {110, B110},
    {134, B134},
    {150, B150},
    {200, B200},
    {300, B300},
    {600, B600},
    {1200, B1200},
    {1800, B1800},
    {2400, B2400},
    {4800, B4800},
    {9600, B9600},
    {19200, B19200},
    {38400, B38400},
    {57600, B57600},
    {115200, B115200},
    {230400, B230400},
    {460800, B460800},
    {500000, B500000},
    {576000, B576000},
    {921600, B921600},
    {1000000, B1000000},
    {1152000, B1152000},
    {1500000, B1500000},
    {2000000, B2000000},
    {2500000, B2500000},
    {3000000, B3000000},
    {3500000, B3500000},
    {4000000, B4000000},
    {0, B0},
}};

IoStatus invalid(const SerialOptions& o, const std::string& what) {
  return IoStatus::Error(IoCode::kInvalidArgument, o.device.empty() ? "serial" : o.device, what);
}

}  // namespace

std::optional<speed_t> baud_to_speed(int baud) {
  for (const auto& [rate, speed] : kBaudRates) {
    if (rate == baud && rate != 0) return speed;
  }
  return std::nullopt;
}

IoStatus SerialOptions::validate() const {
  if (device.empty()) return invalid(*this, "options.device is empty");
  if (!baud_to_speed(baud)) {
    return invalid(*this, "options.baud " + std::to_string(baud) + " is not a standard rate");
  }
  if (data_bits < 5 || data_bits > 8) {
    return invalid(*this, "options.data_bits " + std::to_string(data_bits) + " not in 5..8");
  }
  if (stop_bits != 1 && stop_bits != 2) {
    return invalid(*this, "options.stop_bits " + std::to_string(stop_bits) + " not 1 or 2");
  }
  if (reconnect_initial.count() <= 0 || reconnect_max < reconnect_initial) {
    return invalid(*this, "options.reconnect_initial must be > 0 and <= reconnect_max");
  }
  return IoStatus::Ok();
}

void apply_serial_options(const SerialOptions& o, termios& tio) {
  cfmakeraw(&tio);  // no echo, no line editing, no signals, no CR/LF translation, 8 bits
  tio.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | PARODD | CSTOPB | CRTSCTS);
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY | INPCK | PARMRK | IGNPAR);
  constexpr std::array<tcflag_t, 4> kSizes{CS5, CS6, CS7, CS8};
  tio.c_cflag |= kSizes[static_cast<std::size_t>(o.data_bits - 5)] | CLOCAL | CREAD;
  if (o.parity != Parity::kNone) {
    tio.c_cflag |= PARENB;
    if (o.parity == Parity::kOdd) tio.c_cflag |= PARODD;
    tio.c_iflag |= INPCK | IGNPAR;  // drop characters with parity/framing errors
  }
  if (o.stop_bits == 2) tio.c_cflag |= CSTOPB;
  if (o.flow_control == FlowControl::kHardware) tio.c_cflag |= CRTSCTS;
  if (o.flow_control == FlowControl::kSoftware) tio.c_iflag |= IXON | IXOFF;
  tio.c_cc[VMIN] = 0;  // the fd is non-blocking; poll() does the waiting
  tio.c_cc[VTIME] = 0;
  const speed_t speed = *baud_to_speed(o.baud);
  cfsetispeed(&tio, speed);
  cfsetospeed(&tio, speed);
}

}  // namespace nav::drivers
