#pragma once
// Test helpers for hardware-in-the-loop playback: a private network namespace for LCM udpm
// (PLATFORM.md "LCM 1.3.1": an unprivileged user + network namespace with lo up and the
// multicast route, so parallel tests do not hear each other), and navd as a child process.
#include <arpa/inet.h>
#include <net/if.h>
#include <net/route.h>
#include <netinet/in.h>
#include <sched.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace nav::hil::test {

inline bool write_proc_file(const char* path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  return static_cast<bool>(out.flush());
}

inline void set_ipv4(sockaddr* out, const char* address) {
  auto* in = reinterpret_cast<sockaddr_in*>(out);
  in->sin_family = AF_INET;
  in->sin_addr.s_addr = ::inet_addr(address);
}

/// `ip link set lo up && ip route add 224.0.0.0/4 dev lo`, by ioctl; "" or what failed.
inline std::string loopback_multicast() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return std::string("socket: ") + std::strerror(errno);
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, "lo", IFNAMSIZ - 1);
  std::string error;
  if (::ioctl(fd, SIOCGIFFLAGS, &ifr) != 0) error = "SIOCGIFFLAGS lo";
  ifr.ifr_flags |= IFF_UP;
  if (error.empty() && ::ioctl(fd, SIOCSIFFLAGS, &ifr) != 0) error = "SIOCSIFFLAGS lo up";
  rtentry route{};
  set_ipv4(&route.rt_dst, "224.0.0.0");
  set_ipv4(&route.rt_genmask, "240.0.0.0");
  set_ipv4(&route.rt_gateway, "0.0.0.0");
  route.rt_flags = RTF_UP;
  char lo[] = "lo";
  route.rt_dev = lo;
  if (error.empty() && ::ioctl(fd, SIOCADDRT, &route) != 0) error = "SIOCADDRT 224.0.0.0/4 dev lo";
  if (!error.empty()) error += std::string(": ") + std::strerror(errno);
  ::close(fd);
  return error;
}

/// Moves this (still single-threaded) process into a new user + network namespace with `lo`
/// up and 224.0.0.0/4 routed to it. "" on success, else why not (the caller then uses the
/// host's network). Children started afterwards share the namespace.
inline std::string enter_private_network() {
  const uid_t uid = ::getuid();
  const gid_t gid = ::getgid();
  if (::unshare(CLONE_NEWUSER | CLONE_NEWNET) != 0) {
    return std::string("unshare(CLONE_NEWUSER | CLONE_NEWNET): ") + std::strerror(errno);
  }
  if (!write_proc_file("/proc/self/setgroups", "deny") ||
      !write_proc_file("/proc/self/uid_map", "0 " + std::to_string(uid) + " 1") ||
      !write_proc_file("/proc/self/gid_map", "0 " + std::to_string(gid) + " 1")) {
    return "cannot write the namespace's uid/gid maps";
  }
  return loopback_multicast();
}

/// Starts NAVD_PATH with `args`, stdout and stderr to files in `dir`.
inline pid_t spawn_navd(const std::vector<std::string>& args, const std::filesystem::path& dir) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::vector<std::string> copy = args;
    std::vector<char*> argv{const_cast<char*>(NAVD_PATH)};
    for (std::string& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (!std::freopen((dir / "navd.stdout").c_str(), "w", stdout) ||
        !std::freopen((dir / "navd.stderr").c_str(), "w", stderr)) {
      ::_exit(126);
    }
    ::execv(NAVD_PATH, argv.data());
    ::_exit(127);
  }
  return pid;
}

/// Waits up to `timeout` for `pid`; its exit code, -1 if still running or signalled.
inline int wait_exit(pid_t pid, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  do {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  } while (std::chrono::steady_clock::now() < deadline);
  return -1;
}

}  // namespace nav::hil::test
