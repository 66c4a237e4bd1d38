#pragma once
// The real navd binary (NAVD_PATH, a compile definition of the test) as a child process of a
// test: started with arguments, its stdout and stderr in `dir`/navd.stdout and navd.stderr,
// and waited for with a deadline. Header-only: daemon and hil-tests.
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace nav::tool::test {

/// Starts NAVD_PATH with `args`, stdout and stderr to `dir`/navd.stdout and navd.stderr.
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

}  // namespace nav::tool::test
