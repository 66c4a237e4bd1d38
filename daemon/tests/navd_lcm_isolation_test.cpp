// The network namespace the navd LCM tests run in (support/net_namespace.h): udpm works inside
// it (ttl=0 loops back), a process in the same namespace (navd, a child) is heard, and a
// process publishing on the same group and port from another namespace (another test running
// in parallel under ctest -j) is not.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>

#include "support/net_namespace.h"
#include "support/udpm_probe.h"

namespace {

using nav::tool::test::kIsolatedUdpmUrl;

const nav::tool::test::NetNamespace& kNet = nav::tool::test::isolated_network();

constexpr const char* kChannel = "NAVD_ISOLATION_TEST";

/// Forks a child that (in a namespace of its own when `own_namespace`) publishes on kChannel for
/// ~1 s; its exit code is 0 when it could publish and heard its own messages, else 3.
pid_t spawn_publisher(bool own_namespace) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  if (own_namespace && !nav::tool::test::enter_isolated_network().ok) ::_exit(3);
  lcm::LCM lcm(kIsolatedUdpmUrl);
  if (!lcm.good() || !nav::tool::test::udpm_loops_back(lcm, "NAVD_ISOLATION_CHILD_PROBE")) {
    ::_exit(3);
  }
  const std::uint8_t byte = 7;
  for (int i = 0; i < 40; ++i) {
    lcm.publish(kChannel, &byte, 1);
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  ::_exit(0);
}

/// Messages heard on kChannel while `child` runs; its exit code in `child_code`.
int listen_while(lcm::LCM& lcm, pid_t child, int* child_code) {
  int heard = 0;
  struct Counter {
    int* n;
    void on(const lcm::ReceiveBuffer*, const std::string&) { ++*n; }
  } counter{&heard};
  auto* sub = lcm.subscribe(kChannel, &Counter::on, &counter);
  int status = 0;
  while (::waitpid(child, &status, WNOHANG) == 0) lcm.handleTimeout(20);
  for (int i = 0; i < 5; ++i) lcm.handleTimeout(20);
  lcm.unsubscribe(sub);
  *child_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return heard;
}

TEST(LcmIsolation, UdpmLoopsBackInTheTestsNamespace) {
  if (!kNet.ok) GTEST_SKIP() << kNet.reason;
  lcm::LCM lcm(kIsolatedUdpmUrl);
  ASSERT_TRUE(lcm.good()) << "LCM cannot open " << kIsolatedUdpmUrl << " in the namespace";
  EXPECT_TRUE(nav::tool::test::udpm_loops_back(lcm, "NAVD_ISOLATION_PROBE"));
}

TEST(LcmIsolation, ChildInTheSameNamespaceIsHeard) {
  if (!kNet.ok) GTEST_SKIP() << kNet.reason;
  lcm::LCM lcm(kIsolatedUdpmUrl);
  ASSERT_TRUE(lcm.good());
  int code = -1;
  const int heard = listen_while(lcm, spawn_publisher(false), &code);
  EXPECT_EQ(code, 0);
  EXPECT_GE(heard, 20);  // 40 sent on loopback
}

TEST(LcmIsolation, ProcessInAnotherNamespaceIsNotHeardOnTheSameGroupAndPort) {
  if (!kNet.ok) GTEST_SKIP() << kNet.reason;
  lcm::LCM lcm(kIsolatedUdpmUrl);
  ASSERT_TRUE(lcm.good());
  int code = -1;
  const int heard = listen_while(lcm, spawn_publisher(true), &code);
  ASSERT_EQ(code, 0) << "the child could not publish in its own namespace";  // it heard itself
  EXPECT_EQ(heard, 0);
}

}  // namespace
