// PtyLink: openpty + raw mode + symlink; see pty_link.h.
#include "nav/hil/pty_link.h"

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace nav::hil {
namespace {

[[noreturn]] void fail(const std::filesystem::path& link, const std::string& what, int err) {
  throw std::runtime_error("pty for " + link.string() + ": " + what + ": " + std::strerror(err));
}

}  // namespace

PtyLink::PtyLink(std::filesystem::path link_path) : link_path_(std::move(link_path)) {
  int slave = -1;
  char name[256] = {};
  if (::openpty(&master_, &slave, name, nullptr, nullptr) != 0) fail(link_path_, "openpty", errno);
  slave_path_ = name;
  termios raw{};
  if (::tcgetattr(slave, &raw) == 0) {
    ::cfmakeraw(&raw);
    (void)::tcsetattr(slave, TCSANOW, &raw);
  }
  ::close(slave);
  // Close-on-exec: a reader this process forks and execs (navd in the HIL tests and the fault
  // campaign) must not inherit the master, else closing it here would not hang the line up.
  const int flags = ::fcntl(master_, F_GETFL);
  if (flags < 0 || ::fcntl(master_, F_SETFL, flags | O_NONBLOCK) != 0 ||
      ::fcntl(master_, F_SETFD, FD_CLOEXEC) != 0) {
    const int err = errno;
    ::close(master_);
    fail(link_path_, "fcntl(O_NONBLOCK, FD_CLOEXEC)", err);
  }
  std::error_code ec;
  if (std::filesystem::is_symlink(std::filesystem::symlink_status(link_path_, ec))) {
    std::filesystem::remove(link_path_, ec);
  }
  std::filesystem::create_symlink(slave_path_, link_path_, ec);
  if (ec) {
    ::close(master_);
    fail(link_path_, "symlink to " + slave_path_, ec.value());
  }
}

PtyLink::~PtyLink() {
  std::error_code ec;
  std::filesystem::remove(link_path_, ec);
  if (master_ >= 0) ::close(master_);
}

bool PtyLink::reader_attached() const {
  pollfd p{master_, POLLOUT, 0};
  if (::poll(&p, 1, 0) < 0) return false;
  return (p.revents & POLLHUP) == 0;
}

std::size_t PtyLink::write(std::span<const std::uint8_t> bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(master_, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      break;  // EAGAIN (buffer full), EIO (no reader): the rest is dropped
    }
  }
  return done;
}

}  // namespace nav::hil
