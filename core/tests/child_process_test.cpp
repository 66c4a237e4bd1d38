// The test helper that stops child processes (core/tests/support/nav/testing/child_process.h).
#include "nav/testing/child_process.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>

namespace nav::testing {
namespace {

using namespace std::chrono_literals;

/// A child that sleeps (default SIGTERM action), or ignores SIGTERM when `ignore_term`.
pid_t sleeping_child(bool ignore_term) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (ignore_term) ::signal(SIGTERM, SIG_IGN);
    for (;;) ::pause();
  }
  return pid;
}

TEST(TerminateChild, AChildThatExitsOnSigtermIsReapedWithinTheGrace) {
  const pid_t pid = sleeping_child(false);
  ASSERT_GT(pid, 0);
  EXPECT_TRUE(terminate_child(pid, 5s));
  EXPECT_EQ(::waitpid(pid, nullptr, WNOHANG), -1);  // reaped: no longer our child
}

TEST(TerminateChild, AChildThatIgnoresSigtermIsKilledAfterTheGrace) {
  const pid_t pid = sleeping_child(true);
  ASSERT_GT(pid, 0);
  ::usleep(50'000);  // let it install SIG_IGN
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(terminate_child(pid, 200ms));
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 200ms);
  EXPECT_EQ(::waitpid(pid, nullptr, WNOHANG), -1);  // reaped
}

TEST(TerminateChild, NoPidIsANoOp) { EXPECT_TRUE(terminate_child(-1)); }

}  // namespace
}  // namespace nav::testing
