// termios serial port: exclusive open, raw configuration, poll-based I/O with timeouts, and
// reconnection with exponential backoff after the device vanishes (see serial_port.h).

#include "nav/drivers/transports/serial_port.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <thread>

#include "serial_termios.h"

namespace nav::drivers {
namespace {

using std::chrono::duration_cast;
using std::chrono::milliseconds;

int remaining_ms(std::chrono::steady_clock::time_point deadline) {
  const auto left = duration_cast<milliseconds>(deadline - std::chrono::steady_clock::now());
  return static_cast<int>(std::max<int64_t>(0, left.count()));
}

bool is_vanish_errno(int e) { return e == EIO || e == ENXIO || e == ENODEV || e == EPIPE; }

}  // namespace

SerialPort::SerialPort(SerialOptions options)
    : options_(std::move(options)), options_status_(options_.validate()) {}

SerialPort::~SerialPort() { close(); }

IoStatus SerialPort::open() {
  if (!options_status_.ok()) return options_status_;
  if (fd_ >= 0) return IoStatus::Ok();
  const int fd = ::open(options_.device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    ++stats_.open_failures;
    return IoStatus::FromErrno(errno, options_.device, "open");
  }
  fd_ = fd;
  IoStatus status = configure();
  if (!status.ok()) {
    ++stats_.open_failures;
    close();
    return status;
  }
  if (was_connected_) ++stats_.reconnects;
  was_connected_ = true;
  backoff_ = milliseconds{0};
  return IoStatus::Ok();
}

IoStatus SerialPort::configure() {
  if (options_.exclusive) {
    // flock works across processes even for root, which TIOCEXCL does not stop.
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      return IoStatus::Error(IoCode::kBusy, options_.device, "flock: device in use", errno);
    }
    if (::ioctl(fd_, TIOCEXCL) != 0) return IoStatus::FromErrno(errno, options_.device, "TIOCEXCL");
  }
  termios tio{};
  if (::tcgetattr(fd_, &tio) != 0) {
    return IoStatus::FromErrno(errno, options_.device, "tcgetattr (not a tty?)");
  }
  apply_serial_options(options_, tio);
  if (::tcsetattr(fd_, TCSANOW, &tio) != 0)
    return IoStatus::FromErrno(errno, options_.device, "tcsetattr");
  // tcsetattr succeeds if ANY change was applied: read back to catch a refused rate or framing.
  termios check{};
  if (::tcgetattr(fd_, &check) != 0)
    return IoStatus::FromErrno(errno, options_.device, "tcgetattr");
  constexpr tcflag_t kFraming = CSIZE | PARENB | PARODD;
  if (cfgetospeed(&check) != cfgetospeed(&tio) ||
      (check.c_cflag & kFraming) != (tio.c_cflag & kFraming)) {
    // e.g. a pseudo-terminal forces CS8 without parity (Linux pty_set_termios).
    return IoStatus::Error(
        IoCode::kUnsupported, options_.device,
        "device refused baud " + std::to_string(options_.baud) + ", data bits or parity");
  }
  ::tcflush(fd_, TCIOFLUSH);  // drop bytes queued before we owned the line
  return IoStatus::Ok();
}

void SerialPort::close() {
  if (fd_ >= 0) {
    ::close(fd_);  // releases the flock; TIOCEXCL ends with the last close
    fd_ = -1;
  }
}

IoStatus SerialPort::handle_disconnect(IoStatus reason) {
  close();
  ++stats_.disconnects;
  backoff_ = options_.reconnect_initial;
  next_attempt_ = Clock::now() + backoff_;
  return reason;
}

IoStatus SerialPort::ensure_open(Clock::time_point now) {
  if (!options_status_.ok()) return options_status_;
  if (fd_ >= 0) return IoStatus::Ok();
  if (now < next_attempt_) {
    return IoStatus::Error(IoCode::kDisconnected, options_.device, "waiting to reconnect");
  }
  IoStatus status = open();
  if (!status.ok()) {
    backoff_ = std::clamp(backoff_ * 2, options_.reconnect_initial, options_.reconnect_max);
    next_attempt_ = now + backoff_;
    if (status.code() != IoCode::kBusy && status.code() != IoCode::kInvalidArgument) {
      // A missing device node (ENOENT) while reconnecting is still "disconnected".
      return IoStatus::Error(IoCode::kDisconnected, options_.device, status.message());
    }
  }
  return status;
}

ReadResult SerialPort::read(std::span<uint8_t> buffer, std::chrono::milliseconds timeout) {
  if (buffer.empty()) {  // read(2) of 0 bytes returns 0, which would look like a hang-up
    return {
        IoStatus::Error(IoCode::kInvalidArgument, options_.device, "read: empty buffer"), 0, {}};
  }
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    IoStatus open_status = ensure_open(Clock::now());
    if (!open_status.ok()) {
      if (open_status.code() != IoCode::kDisconnected || Clock::now() >= deadline) {
        return {std::move(open_status), 0, {}};
      }
      std::this_thread::sleep_until(std::min(deadline, next_attempt_));
      continue;
    }
    pollfd pfd{fd_, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, remaining_ms(deadline));
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) return {IoStatus::FromErrno(errno, options_.device, "poll"), 0, {}};
    if (ready == 0) {
      return {IoStatus::Error(IoCode::kTimeout, options_.device, "read: no data within timeout"),
              0,
              {}};
    }
    const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
    const HostTime received = host_time_now();
    if (n > 0) {
      stats_.bytes_read += static_cast<uint64_t>(n);
      return {IoStatus::Ok(), static_cast<std::size_t>(n), received};
    }
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
    // read() == 0 after POLLIN, POLLHUP, or EIO/ENXIO: the device is gone.
    const int err = n < 0 ? errno : EIO;
    if (n < 0 && !is_vanish_errno(err))
      return {IoStatus::FromErrno(err, options_.device, "read"), 0, {}};
    return {handle_disconnect(IoStatus::Error(IoCode::kDisconnected, options_.device,
                                              "device vanished (read)", err)),
            0,
            {}};
  }
}

IoStatus SerialPort::write(std::span<const uint8_t> bytes, std::chrono::milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  IoStatus open_status = ensure_open(Clock::now());
  if (!open_status.ok()) return open_status;
  std::size_t done = 0;
  while (done < bytes.size()) {
    pollfd pfd{fd_, POLLOUT, 0};
    const int ready = ::poll(&pfd, 1, remaining_ms(deadline));
    if (ready < 0 && errno == EINTR) continue;
    if (ready == 0) {
      return IoStatus::Error(IoCode::kTimeout, options_.device,
                             "write: " + std::to_string(bytes.size() - done) + " bytes not sent");
    }
    const ssize_t n = ready < 0 ? -1 : ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      stats_.bytes_written += static_cast<uint64_t>(n);
      continue;
    }
    if (n < 0 && (errno == EAGAIN || errno == EINTR)) continue;
    const int err = n < 0 ? errno : EIO;
    if (is_vanish_errno(err) || (pfd.revents & (POLLHUP | POLLERR)) != 0) {
      return handle_disconnect(
          IoStatus::Error(IoCode::kDisconnected, options_.device, "device vanished (write)", err));
    }
    return IoStatus::FromErrno(err, options_.device, "write");
  }
  return IoStatus::Ok();
}

}  // namespace nav::drivers
