// GVCP READREG liveness probe (gvcp_probe.h).

#include "gvcp_probe.h"

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <system_error>

namespace nav::drivers {
namespace {

constexpr std::uint8_t kGvcpKey = 0x42;          // first byte of every command
constexpr std::uint8_t kFlagAcknowledge = 0x01;  // the device must acknowledge
constexpr std::uint16_t kReadRegCmd = 0x0080;
constexpr std::uint16_t kReadRegAck = 0x0081;
constexpr std::uint32_t kVersionRegister = 0x0000;  // bootstrap register every device has

void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v);
}

std::uint16_t get_u16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

std::string address_text(const sockaddr_in& a) {
  char host[INET_ADDRSTRLEN] = "?";
  inet_ntop(AF_INET, &a.sin_addr, host, sizeof host);
  return std::string(host) + ":" + std::to_string(ntohs(a.sin_port));
}

}  // namespace

GvcpProbe::GvcpProbe(const sockaddr_in& device, std::chrono::milliseconds try_timeout, int tries)
    : device_(device), try_timeout_(try_timeout), tries_(tries) {
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "GvcpProbe: socket");
}

GvcpProbe::~GvcpProbe() {
  if (fd_ >= 0) ::close(fd_);
}

bool GvcpProbe::answers(std::string* why) {
  for (int i = 0; i < tries_; ++i) {
    if (try_once()) return true;
  }
  if (why != nullptr) {
    *why = "no READREG_ACK from " + address_text(device_) + " in " + std::to_string(tries_) +
           " x " + std::to_string(try_timeout_.count()) + " ms";
  }
  return false;
}

bool GvcpProbe::try_once() {
  request_id_ = static_cast<std::uint16_t>(request_id_ == 0xffff ? 1 : request_id_ + 1);
  std::array<std::uint8_t, 12> cmd{};
  cmd[0] = kGvcpKey;
  cmd[1] = kFlagAcknowledge;
  put_u16(&cmd[2], kReadRegCmd);
  put_u16(&cmd[4], 4);  // payload: one register address
  put_u16(&cmd[6], request_id_);
  put_u16(&cmd[8], static_cast<std::uint16_t>(kVersionRegister >> 16));
  put_u16(&cmd[10], static_cast<std::uint16_t>(kVersionRegister));
  if (::sendto(fd_, cmd.data(), cmd.size(), 0, reinterpret_cast<const sockaddr*>(&device_),
               sizeof device_) != static_cast<ssize_t>(cmd.size())) {
    return false;
  }
  const auto deadline = std::chrono::steady_clock::now() + try_timeout_;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd p{fd_, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) return false;
    std::array<std::uint8_t, 64> ack{};
    sockaddr_in from{};
    socklen_t from_len = sizeof from;
    const ssize_t n =
        ::recvfrom(fd_, ack.data(), ack.size(), 0, reinterpret_cast<sockaddr*>(&from), &from_len);
    // An acknowledge of this request from the device; anything else (a late answer to an
    // earlier try, a stray datagram) is skipped.
    if (n >= 8 && from.sin_addr.s_addr == device_.sin_addr.s_addr &&
        get_u16(&ack[2]) == kReadRegAck && get_u16(&ack[6]) == request_id_) {
      return true;
    }
  }
}

}  // namespace nav::drivers
