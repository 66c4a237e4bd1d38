// Host faults and processes of the fault campaign; see host_faults.h. The route and interface
// ioctls are what `ip link set lo up` / `ip route add|del 224.0.0.0/4 dev lo` do (netdevice(7),
// SIOCADDRT/SIOCDELRT of route(7)); the mount calls what `mount --make-rprivate /` and
// `mount -t tmpfs -o size=N` do (mount(2)).
#include "host_faults.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <net/if.h>
#include <net/route.h>
#include <netinet/in.h>
#include <sched.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/mount.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

namespace nav::campaign {
namespace {

std::string errno_text(const std::string& what) { return what + ": " + std::strerror(errno); }

std::string route_ioctl(unsigned long request, const char* what) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return errno_text("socket(AF_INET)");
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
  std::string error;
  if (::ioctl(fd, request, &route) != 0) error = errno_text(what);
  ::close(fd);
  return error;
}

std::string loopback_up() {
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return errno_text("socket(AF_INET)");
  ifreq ifr{};
  std::strncpy(ifr.ifr_name, "lo", IFNAMSIZ - 1);
  std::string error;
  if (::ioctl(fd, SIOCGIFFLAGS, &ifr) != 0) {
    error = errno_text("ioctl(SIOCGIFFLAGS, lo)");
  } else if (ifr.ifr_flags |= IFF_UP; ::ioctl(fd, SIOCSIFFLAGS, &ifr) != 0) {
    error = errno_text("ioctl(SIOCSIFFLAGS, lo up)");
  }
  ::close(fd);
  return error;
}

}  // namespace

std::string enter_private_namespaces() {
  if (::unshare(CLONE_NEWNET) != 0) return errno_text("unshare(CLONE_NEWNET)");
  if (std::string e = loopback_up(); !e.empty()) return e;
  if (std::string e = add_multicast_route(); !e.empty()) return e;
  if (::unshare(CLONE_NEWNS) != 0) return errno_text("unshare(CLONE_NEWNS)");
  if (::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) {
    return errno_text("mount(/, MS_REC | MS_PRIVATE)");
  }
  return {};
}

std::string delete_multicast_route() {
  return route_ioctl(SIOCDELRT, "ioctl(SIOCDELRT, 224.0.0.0/4 dev lo)");
}

std::string add_multicast_route() {
  return route_ioctl(SIOCADDRT, "ioctl(SIOCADDRT, 224.0.0.0/4 dev lo)");
}

std::string mount_small_tmpfs(const std::filesystem::path& dir, int size_kib) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const std::string data = "size=" + std::to_string(size_kib) + "k";
  if (::mount("tmpfs", dir.c_str(), "tmpfs", 0, data.c_str()) != 0) {
    return errno_text("mount tmpfs " + data + " on " + dir.string());
  }
  return {};
}

std::string unmount(const std::filesystem::path& dir) {
  if (::umount2(dir.c_str(), MNT_DETACH) != 0) return errno_text("umount " + dir.string());
  return {};
}

std::string fill_until_full(const std::filesystem::path& file) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return errno_text("open " + file.string());
  static const char block[4096] = {};
  std::string error;
  for (;;) {
    if (::write(fd, block, sizeof block) < 0) {
      if (errno != ENOSPC) error = errno_text("write " + file.string());
      break;
    }
  }
  ::close(fd);
  return error;
}

std::vector<pid_t> start_cpu_burners(int count) {
  std::vector<pid_t> pids;
  for (int i = 0; i < count; ++i) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      volatile std::uint64_t x = 0;
      for (;;) x = x + 1;  // killed by stop_processes
    }
    if (pid > 0) pids.push_back(pid);
  }
  return pids;
}

void stop_processes(const std::vector<pid_t>& pids) {
  for (pid_t pid : pids) {
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
  }
}

pid_t spawn_logged(const std::filesystem::path& program, const std::vector<std::string>& args,
                   const std::filesystem::path& dir) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::vector<std::string> copy = args;
    std::string path = program.string();
    std::vector<char*> argv{path.data()};
    for (std::string& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (!std::freopen((dir / "navd.stdout").c_str(), "a", stdout) ||
        !std::freopen((dir / "navd.stderr").c_str(), "a", stderr)) {
      ::_exit(126);
    }
    ::execv(path.c_str(), argv.data());
    ::_exit(127);
  }
  return pid;
}

int wait_exit_ms(pid_t pid, int timeout_ms, bool* still_running) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  do {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      if (still_running) *still_running = false;
      return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  } while (std::chrono::steady_clock::now() < deadline);
  if (still_running) *still_running = true;
  return -1;
}

}  // namespace nav::campaign
