#pragma once
// Child processes of the topside tests: `navtool topside`, node scripts, navd. Each child
// inherits the test's isolated network namespace (net_namespace.h), so its LCM and its TCP
// port are the test's own. Header-only.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "nav/testing/child_process.h"

namespace nav::tool::test {

/// Starts argv[0] (a path) with stdout and stderr to the given files.
inline pid_t spawn_process(const std::vector<std::string>& argv, const std::filesystem::path& out,
                           const std::filesystem::path& err) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::vector<std::string> copy = argv;
    std::vector<char*> args;
    for (std::string& a : copy) args.push_back(a.data());
    args.push_back(nullptr);
    if (!std::freopen(out.c_str(), "w", stdout) || !std::freopen(err.c_str(), "w", stderr)) {
      ::_exit(126);
    }
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  return pid;
}

/// Waits up to `timeout` for `pid`; its exit code, -1 if still running or signalled.
inline int wait_child(pid_t pid, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  do {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid)
      return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  } while (std::chrono::steady_clock::now() < deadline);
  return -1;
}

/// SIGTERM, then SIGKILL after 3 s; reaps the child (nav/testing/child_process.h).
inline void stop_child(pid_t pid) {
  (void)nav::testing::terminate_child(pid, std::chrono::seconds(3));
}

inline std::string file_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Starts `navtool topside` on 127.0.0.1:`port` and waits for its {"url": ...} line; the pid
/// (stop it with stop_child) or -1 if it did not come up within 10 s.
/// `extra`: more arguments (e.g. --config).
inline pid_t start_topside(const std::string& lcm_url, int port, const std::filesystem::path& dir,
                           const std::vector<std::string>& extra = {}) {
  std::vector<std::string> argv = {NAVTOOL_PATH, "topside",  "--lcm-url",
                                   lcm_url,      "--listen", "127.0.0.1:" + std::to_string(port)};
  argv.insert(argv.end(), extra.begin(), extra.end());
  const pid_t pid = spawn_process(argv, dir / "topside.stdout", dir / "topside.stderr");
  for (int i = 0; i < 500; ++i) {
    if (file_text(dir / "topside.stdout").find("\"url\"") != std::string::npos) return pid;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  stop_child(pid);
  return -1;
}

}  // namespace nav::tool::test
