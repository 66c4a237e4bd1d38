#pragma once
// termios serial port (POSIX.1 General Terminal Interface, termios(3); Linux tty_ioctl(4)) as a
// ByteStream: raw 8-bit mode, baud / data bits / parity / stop bits / flow control from
// SerialOptions, exclusive open (TIOCEXCL + flock), poll(2)-based reads with a timeout, and
// automatic reconnection with exponential backoff after the device disappears (USB-serial
// adapter unplugged, pty peer closed: EIO / ENXIO / ENODEV / POLLHUP).
//
// Threading: one driver thread owns a SerialPort and calls read()/write(); nothing blocks longer
// than the timeout passed in. The port is opened by open() or, lazily, by the first read()/write().
// After a disconnect, read()/write() return kDisconnected once (the error is reported), then keep
// retrying the open at the backoff schedule inside later calls until the device is back.

#include <chrono>
#include <cstdint>
#include <string>

#include "nav/drivers/transports/byte_stream.h"

namespace nav::drivers {

enum class Parity { kNone, kEven, kOdd };
enum class FlowControl { kNone, kHardware /* RTS/CTS */, kSoftware /* XON/XOFF */ };

struct SerialOptions {
  /// Device path, e.g. /dev/ttyUSB0 or a stable /dev/serial/by-id/... link. Required.
  std::string device;
  /// Line rate in bit/s; one of the POSIX/Linux standard rates 50 ... 4000000.
  int baud = 9600;
  /// Data bits per character: 5, 6, 7 or 8.
  int data_bits = 8;
  /// Parity; when not kNone, received characters with parity errors are discarded (INPCK).
  Parity parity = Parity::kNone;
  /// Stop bits: 1 or 2.
  int stop_bits = 1;
  FlowControl flow_control = FlowControl::kNone;
  /// Refuse to share the device with other processes (TIOCEXCL and an advisory flock).
  bool exclusive = true;
  /// First delay between reopen attempts after a disconnect; doubles up to reconnect_max.
  std::chrono::milliseconds reconnect_initial{100};
  std::chrono::milliseconds reconnect_max{5000};

  /// Ok, or kInvalidArgument naming the offending field and value.
  IoStatus validate() const;
};

class SerialPort final : public ByteStream {
 public:
  struct Stats {
    uint64_t bytes_read = 0;
    uint64_t bytes_written = 0;
    uint64_t disconnects = 0;    ///< times the open device vanished
    uint64_t reconnects = 0;     ///< successful reopens after a disconnect
    uint64_t open_failures = 0;  ///< failed open attempts (including during reconnection)
  };

  /// Does not open the device. Invalid options make every call fail with the validate() reason.
  explicit SerialPort(SerialOptions options);
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  /// Opens and configures the device now (raw mode, flushes stale input).
  IoStatus open();
  void close();
  bool is_open() const { return fd_ >= 0; }

  ReadResult read(std::span<uint8_t> buffer, std::chrono::milliseconds timeout) override;
  IoStatus write(std::span<const uint8_t> bytes, std::chrono::milliseconds timeout) override;
  const std::string& name() const override { return options_.device; }

  const Stats& stats() const { return stats_; }
  const SerialOptions& options() const { return options_; }
  /// The open file descriptor (-1 when closed), e.g. for tcgetattr in tests.
  int native_handle() const { return fd_; }

 private:
  using Clock = std::chrono::steady_clock;
  IoStatus configure();
  /// Opens if closed and a reconnect attempt is due; Ok when the port is open afterwards.
  IoStatus ensure_open(Clock::time_point now);
  /// Closes after the device vanished and schedules the first reopen attempt.
  IoStatus handle_disconnect(IoStatus reason);

  SerialOptions options_;
  IoStatus options_status_;
  int fd_ = -1;
  bool was_connected_ = false;
  std::chrono::milliseconds backoff_{0};
  Clock::time_point next_attempt_{};
  Stats stats_;
};

}  // namespace nav::drivers
