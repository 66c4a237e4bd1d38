// SIGTERM, a grace period, then SIGKILL (nav/testing/child_process.h).
#include "nav/testing/child_process.h"

#include <signal.h>
#include <sys/wait.h>

#include <thread>

namespace nav::testing {

bool terminate_child(pid_t pid, std::chrono::milliseconds grace) {
  if (pid <= 0) return true;
  ::kill(pid, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + grace;
  while (std::chrono::steady_clock::now() < deadline) {
    const pid_t r = ::waitpid(pid, nullptr, WNOHANG);
    if (r == pid) return true;
    if (r < 0) return false;  // not our child (or already reaped)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  return false;
}

}  // namespace nav::testing
