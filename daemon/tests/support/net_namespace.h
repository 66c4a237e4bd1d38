#pragma once
// An isolated network namespace per test process for tests that talk LCM udpm
// (docs/platform.md "LCM"): the process moves into a new network namespace whose only interface is
// `lo`, brought up, with the multicast route 224.0.0.0/4 dev lo (what `unshare -rn sh -c 'ip
// link set lo up && ip route add 224.0.0.0/4 dev lo'` does, here with ioctls so no tool is
// needed). Child processes (navd) inherit it, so a test hears exactly its own navd, and tests
// running in parallel (ctest -j) cannot hear each other whatever ports they use.
// As root CLONE_NEWNET alone; otherwise CLONE_NEWUSER | CLONE_NEWNET with this user mapped to
// root inside (unprivileged user namespaces). CLONE_NEWUSER needs a single-threaded process, so
// call isolated_network() before any thread starts: from a namespace-scope initialiser of the
// test file, e.g.
//     const auto& kNet = nav::tool::test::isolated_network();
// and skip with kNet.reason where !kNet.ok (namespaces not permitted, e.g. inside a container
// without CAP_SYS_ADMIN and with user namespaces disabled). Header-only: daemon and hil-tests.
#include <arpa/inet.h>
#include <net/if.h>
#include <net/route.h>
#include <netinet/in.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <string>

namespace nav::tool::test {

/// The LCM URL the isolated tests use (any fixed one: each test has its own multicast world).
inline constexpr const char* kIsolatedUdpmUrl = "udpm://239.255.76.67:7667?ttl=0";

struct NetNamespace {
  bool ok = false;
  std::string reason;  ///< why not (for GTEST_SKIP), empty when ok
};

namespace detail {

inline std::string errno_text(const std::string& what) {
  return what + ": " + std::strerror(errno);
}

inline bool write_proc(const std::string& path, const std::string& text, std::string* error) {
  std::ofstream out(path);
  out << text;
  out.close();
  if (!out) *error = "cannot write '" + text + "' to " + path;
  return static_cast<bool>(out);
}

/// unshare(2) into a new network namespace (and a user namespace when not root).
inline bool unshare_network(std::string* error) {
  if (::geteuid() == 0) {
    if (::unshare(CLONE_NEWNET) == 0) return true;
    *error = errno_text("unshare(CLONE_NEWNET) as root");
    return false;
  }
  const uid_t uid = ::geteuid();
  const gid_t gid = ::getegid();
  if (::unshare(CLONE_NEWUSER | CLONE_NEWNET) != 0) {
    *error = errno_text("unshare(CLONE_NEWUSER | CLONE_NEWNET)");
    return false;
  }
  return write_proc("/proc/self/setgroups", "deny", error) &&
         write_proc("/proc/self/uid_map", "0 " + std::to_string(uid) + " 1", error) &&
         write_proc("/proc/self/gid_map", "0 " + std::to_string(gid) + " 1", error);
}

/// ip link set lo up; ip route add 224.0.0.0/4 dev lo.
inline bool loopback_multicast(std::string* error) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    *error = errno_text("socket(AF_INET) in the new namespace");
    return false;
  }
  bool ok = false;
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, "lo", IFNAMSIZ - 1);
  rtentry route{};
  auto* dst = reinterpret_cast<sockaddr_in*>(&route.rt_dst);
  auto* mask = reinterpret_cast<sockaddr_in*>(&route.rt_genmask);
  dst->sin_family = AF_INET;
  dst->sin_addr.s_addr = htonl(0xE0000000u);  // 224.0.0.0
  mask->sin_family = AF_INET;
  mask->sin_addr.s_addr = htonl(0xF0000000u);  // /4
  route.rt_flags = RTF_UP;
  char lo[] = "lo";
  route.rt_dev = lo;
  if (::ioctl(fd, SIOCGIFFLAGS, &ifr) != 0) {
    *error = errno_text("ioctl(SIOCGIFFLAGS, lo)");
  } else if (ifr.ifr_flags |= IFF_UP; ::ioctl(fd, SIOCSIFFLAGS, &ifr) != 0) {
    *error = errno_text("ioctl(SIOCSIFFLAGS, lo up)");
  } else if (::ioctl(fd, SIOCADDRT, &route) != 0) {
    *error = errno_text("ioctl(SIOCADDRT, 224.0.0.0/4 dev lo)");
  } else {
    ok = true;
  }
  ::close(fd);
  return ok;
}

}  // namespace detail

/// Moves this process (and its future children) into a new network namespace with multicast
/// on `lo`; see the file comment. Not idempotent: call once (isolated_network()).
inline NetNamespace enter_isolated_network() {
  NetNamespace ns;
  std::string error;
  if (!detail::unshare_network(&error) || !detail::loopback_multicast(&error)) {
    ns.reason = "no isolated network namespace for LCM udpm: " + error;
    return ns;
  }
  ns.ok = true;
  return ns;
}

/// Moves this process into a new network namespace with `lo` down and no route at all: LCM
/// udpm cannot be opened there (tests of that failure; call in a forked child).
inline NetNamespace enter_network_without_multicast() {
  NetNamespace ns;
  if (!detail::unshare_network(&ns.reason)) return ns;
  ns.ok = true;
  return ns;
}

/// The process's isolated network, entered at the first call (before any thread starts).
inline const NetNamespace& isolated_network() {
  static const NetNamespace ns = enter_isolated_network();
  return ns;
}

}  // namespace nav::tool::test
