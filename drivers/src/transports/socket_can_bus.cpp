// SocketCAN raw socket and its socketpair stand-in (see can_bus.h; Linux
// Documentation/networking/can.rst sections 4.1 "RAW protocol sockets with can_filters" and
// 4.1.1-4.1.5 on filters, error frames and timestamps).

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "nav/drivers/transports/can_bus.h"

namespace nav::drivers {
namespace {

using Clock = std::chrono::steady_clock;

int remaining_ms(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
  return static_cast<int>(std::max<int64_t>(0, left.count()));
}

can_frame to_kernel(const CanFrame& f) {
  can_frame k{};
  k.can_id = f.id | (f.extended ? CAN_EFF_FLAG : 0u) | (f.remote ? CAN_RTR_FLAG : 0u);
  k.len = f.dlc;
  std::memcpy(k.data, f.data.data(), f.dlc);
  return k;
}

can_filter to_kernel(const CanFilter& f) {
  const canid_t id_mask = f.extended ? CAN_EFF_MASK : CAN_SFF_MASK;
  return can_filter{(f.id & id_mask) | (f.extended ? CAN_EFF_FLAG : 0u),
                    (f.mask & id_mask) | CAN_EFF_FLAG};
}

}  // namespace

bool can_filter_accepts(const CanFilter& filter, uint32_t id, bool extended) {
  const can_filter k = to_kernel(filter);
  const canid_t raw =
      (id & (extended ? CAN_EFF_MASK : CAN_SFF_MASK)) | (extended ? CAN_EFF_FLAG : 0u);
  return (raw & k.can_mask) == (k.can_id & k.can_mask);
}

IoStatus validate_can_frame(const CanFrame& f) {
  const uint32_t max_id = f.extended ? CAN_EFF_MASK : CAN_SFF_MASK;
  if (f.id > max_id) {
    return IoStatus::Error(
        IoCode::kInvalidArgument, "can",
        "frame id " + std::to_string(f.id) + " exceeds " + (f.extended ? "29" : "11") + " bits");
  }
  if (f.dlc > CAN_MAX_DLEN) {
    return IoStatus::Error(IoCode::kInvalidArgument, "can",
                           "frame dlc " + std::to_string(f.dlc) + " > 8");
  }
  return IoStatus::Ok();
}

SocketCanBus::~SocketCanBus() { close(); }

void SocketCanBus::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

IoStatus SocketCanBus::open_interface(const std::string& interface_name) {
  close();
  name_ = interface_name;
  kernel_can_ = true;
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC | SOCK_NONBLOCK, CAN_RAW);
  if (fd < 0) return IoStatus::FromErrno(errno, name_, "socket(PF_CAN, SOCK_RAW, CAN_RAW)");
  fd_ = fd;
  const unsigned index = ::if_nametoindex(interface_name.c_str());
  if (index == 0) {
    const int err = errno;
    close();
    return IoStatus::Error(IoCode::kDisconnected, name_, "no such CAN interface", err);
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  const can_err_mask_t err_mask = CAN_ERR_MASK;  // deliver every error class; we count them
  const int one = 1;
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask) != 0 ||
      ::setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one) != 0) {
    const IoStatus s = IoStatus::FromErrno(errno, name_, "bind/setsockopt");
    close();
    return s;
  }
  IoStatus s = enable_timestamps();
  if (s.ok()) s = set_filters(filters_);
  if (!s.ok()) close();
  return s;
}

IoStatus SocketCanBus::adopt_socket(int fd, std::string name) {
  close();
  name_ = std::move(name);
  kernel_can_ = false;
  if (fd < 0) return IoStatus::Error(IoCode::kInvalidArgument, name_, "adopt_socket: fd < 0");
  fd_ = fd;
  const int flags = ::fcntl(fd_, F_GETFL);
  if (flags < 0 || ::fcntl(fd_, F_SETFL, flags | O_NONBLOCK) != 0) {
    const IoStatus s = IoStatus::FromErrno(errno, name_, "fcntl(O_NONBLOCK)");
    close();
    return s;
  }
  IoStatus s = enable_timestamps();
  if (!s.ok()) close();
  return s;
}

IoStatus SocketCanBus::enable_timestamps() {
  const int one = 1;
  if (::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &one, sizeof one) != 0) {
    return IoStatus::FromErrno(errno, name_, "setsockopt(SO_TIMESTAMPNS)");
  }
  return IoStatus::Ok();
}

IoStatus SocketCanBus::set_filters(std::span<const CanFilter> filters) {
  if (kernel_can_ && fd_ >= 0) {
    // The kernel treats an empty CAN_RAW_FILTER list as "receive nothing": install accept-all.
    std::vector<can_filter> k;
    for (const CanFilter& f : filters) k.push_back(to_kernel(f));
    if (k.empty()) k.push_back(can_filter{0, 0});
    if (::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, k.data(),
                     static_cast<socklen_t>(k.size() * sizeof(can_filter))) != 0) {
      return IoStatus::FromErrno(errno, name_, "setsockopt(CAN_RAW_FILTER)");
    }
  }
  filters_.assign(filters.begin(), filters.end());
  return IoStatus::Ok();
}

IoStatus SocketCanBus::receive(CanFrame& frame, std::chrono::milliseconds timeout) {
  if (fd_ < 0) return IoStatus::Error(IoCode::kDisconnected, name_, "receive: bus not open");
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    pollfd pfd{fd_, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, remaining_ms(deadline));
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) return IoStatus::FromErrno(errno, name_, "poll");
    if (ready == 0)
      return IoStatus::Error(IoCode::kTimeout, name_, "receive: no frame within timeout");
    bool accepted = false;
    IoStatus s = receive_one(frame, accepted);
    if (!s.ok() || accepted) return s;
    if (Clock::now() >= deadline) {
      return IoStatus::Error(IoCode::kTimeout, name_, "receive: no accepted frame within timeout");
    }
  }
}

IoStatus SocketCanBus::receive_one(CanFrame& frame, bool& accepted) {
  accepted = false;
  alignas(can_frame) uint8_t bytes[sizeof(canfd_frame)];
  alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec)) + CMSG_SPACE(sizeof(uint32_t))];
  iovec iov{bytes, sizeof bytes};
  msghdr msg{};
  msg.msg_iov = &iov;
  msg.msg_iovlen = 1;
  msg.msg_control = control;
  msg.msg_controllen = sizeof control;
  const ssize_t n = ::recvmsg(fd_, &msg, 0);
  const HostTime received = host_time_now();
  if (n < 0) {
    if (errno == EAGAIN || errno == EINTR) return IoStatus::Ok();
    return IoStatus::FromErrno(errno, name_, "recvmsg");
  }
  if (n == 0) return IoStatus::Error(IoCode::kDisconnected, name_, "peer closed the bus socket");
  std::optional<int64_t> kernel_us;
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level != SOL_SOCKET) continue;
    if (c->cmsg_type == SCM_TIMESTAMPNS) {
      timespec ts{};
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      kernel_us = static_cast<int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1'000 +
                  realtime_offset_us();  // on host_time_now()'s realtime (timestamps.h)
    } else if (c->cmsg_type == SO_RXQ_OVFL) {
      uint32_t drops = 0;
      std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
      stats_.kernel_drops = drops;  // cumulative count kept by the kernel
    }
  }
  can_frame k{};
  if (static_cast<std::size_t>(n) != sizeof k || (msg.msg_flags & MSG_TRUNC) != 0) {
    ++stats_.malformed;
    return IoStatus::Ok();
  }
  std::memcpy(&k, bytes, sizeof k);
  if ((k.can_id & CAN_ERR_FLAG) != 0) {
    ++stats_.error_frames;
    stats_.last_error_class = k.can_id & CAN_ERR_MASK;
    return IoStatus::Ok();
  }
  if (k.len > CAN_MAX_DLEN) {
    ++stats_.malformed;
    return IoStatus::Ok();
  }
  const bool extended = (k.can_id & CAN_EFF_FLAG) != 0;
  const uint32_t id = k.can_id & (extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  const bool pass =
      filters_.empty() || std::any_of(filters_.begin(), filters_.end(), [&](const CanFilter& f) {
        return can_filter_accepts(f, id, extended);
      });
  if (!pass) {
    ++stats_.filtered_out;
    return IoStatus::Ok();
  }
  frame.id = id;
  frame.extended = extended;
  frame.remote = (k.can_id & CAN_RTR_FLAG) != 0;
  frame.dlc = k.len;
  frame.data.fill(0);
  std::memcpy(frame.data.data(), k.data, k.len);
  frame.received = received;
  frame.kernel_realtime_us = kernel_us;
  ++stats_.frames_received;
  accepted = true;
  return IoStatus::Ok();
}

IoStatus SocketCanBus::send(const CanFrame& frame, std::chrono::milliseconds timeout) {
  if (fd_ < 0) return IoStatus::Error(IoCode::kDisconnected, name_, "send: bus not open");
  IoStatus valid = validate_can_frame(frame);
  if (!valid.ok()) return IoStatus::Error(IoCode::kInvalidArgument, name_, valid.message());
  const can_frame k = to_kernel(frame);
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    const ssize_t n = ::send(fd_, &k, sizeof k, MSG_NOSIGNAL);
    if (n == static_cast<ssize_t>(sizeof k)) {
      ++stats_.frames_sent;
      return IoStatus::Ok();
    }
    // ENOBUFS: the CAN TX queue is full (the kernel does not block raw CAN sockets).
    if (n < 0 && errno != EAGAIN && errno != ENOBUFS && errno != EINTR) {
      return IoStatus::FromErrno(errno, name_, "send");
    }
    if (Clock::now() >= deadline)
      return IoStatus::Error(IoCode::kTimeout, name_, "send: TX queue full");
    pollfd pfd{fd_, POLLOUT, 0};
    (void)::poll(&pfd, 1, std::min(remaining_ms(deadline), 5));
  }
}

IoStatus open_can_socketpair(SocketCanBus& a, SocketCanBus& b) {
  int fds[2] = {-1, -1};
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds) != 0) {
    return IoStatus::FromErrno(errno, "can-socketpair", "socketpair(AF_UNIX, SOCK_SEQPACKET)");
  }
  IoStatus s = a.adopt_socket(fds[0], "can-socketpair-a");
  if (!s.ok()) {
    ::close(fds[1]);
    return s;
  }
  return b.adopt_socket(fds[1], "can-socketpair-b");
}

}  // namespace nav::drivers
