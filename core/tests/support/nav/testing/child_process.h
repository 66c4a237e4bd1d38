#pragma once
// Stopping a helper process that a test started (socat, a fake camera): SIGTERM first, then
// SIGKILL when it has not exited within a grace period. A plain kill(SIGTERM) + waitpid can wait
// forever: socat 1.7.4 was seen to stay in poll() after a SIGTERM (once, under ASan, with the
// signal caught and none pending), and the test then hung until CTest's timeout.
#include <sys/types.h>

#include <chrono>

namespace nav::testing {

/// Sends SIGTERM to `pid`, waits up to `grace` for it to exit, then sends SIGKILL; reaps it
/// either way. True if it exited within the grace period; false if it had to be killed or was
/// not a child of this process (waitpid failed). pid <= 0 is a no-op (true).
bool terminate_child(pid_t pid, std::chrono::milliseconds grace = std::chrono::seconds(2));

}  // namespace nav::testing
