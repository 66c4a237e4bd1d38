// Real-time scheduling of navd's threads (nav/daemon/system/realtime.h): the priority a thread
// asks for is the one the kernel runs it at, a refusal says why, and navd.service's mechanism
// (no capability, RLIMIT_RTPRIO 50) allows exactly the priorities up to 50. The unprivileged
// case runs in a forked child that drops to user nobody with the unit's limit. keep_freed_memory
// is checked through mallinfo2 in a child of its own.
#include "nav/daemon/system/realtime.h"

#include <gtest/gtest.h>
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "nav/daemon/system/process_usage.h"

namespace nav::daemon {
namespace {

/// Runs `body` on a new thread (so the test's own thread keeps its scheduling) and returns
/// what it returned.
template <typename F>
std::string on_a_thread(F body) {
  std::string out;
  std::thread t([&] { out = body(); });
  t.join();
  return out;
}

/// The calling thread's name as /proc shows it.
std::string this_thread_comm() {
  std::ifstream in("/proc/thread-self/comm");
  std::string name;
  std::getline(in, name);
  return name;
}

TEST(Realtime, PriorityZeroLeavesNormalScheduling) {
  const std::string out =
      on_a_thread([] { return request_fifo_priority(0) + "|" + thread_policy_text(); });
  EXPECT_EQ(out, "|SCHED_OTHER");
}

TEST(Realtime, APriorityOutsideTheKernelsRangeIsRefusedWithTheRange) {
  const std::string out =
      on_a_thread([] { return request_fifo_priority(100) + "|" + thread_policy_text(); });
  EXPECT_EQ(out, "SCHED_FIFO priority 100 is outside [1, 99]|SCHED_OTHER");
}

TEST(Realtime, ThreadNamesAreCutToWhatLinuxKeeps) {
  const std::string out = on_a_thread([] {
    name_this_thread("navd-a_very_long_sensor_name");
    return this_thread_comm();
  });
  EXPECT_EQ(out, "navd-a_very_lon");  // 15 bytes
}

constexpr const char* kCannotSetLimit = "cannot set RLIMIT_RTPRIO";

/// In a forked child: RLIMIT_RTPRIO = `limit`, drop to user nobody (no capability left), then
/// ask for each priority on the child's own thread; the answers, '|'-separated, via a pipe.
std::string as_unprivileged_user(rlim_t limit, const std::array<int, 2>& priorities) {
  int fds[2];
  if (::pipe(fds) != 0) return "pipe failed";
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    const rlimit rl{limit, limit};
    std::string out;
    if (::setrlimit(RLIMIT_RTPRIO, &rl) != 0) {
      out = kCannotSetLimit;
    } else if (::setgid(65534) != 0 || ::setuid(65534) != 0) {
      out = "could not drop privileges";
    } else {
      for (int p : priorities) out += request_fifo_priority(p) + "=" + thread_policy_text() + "|";
    }
    const ssize_t written = ::write(fds[1], out.data(), out.size());
    ::_exit(written == static_cast<ssize_t>(out.size()) ? 0 : 1);
  }
  ::close(fds[1]);
  std::string out;
  std::array<char, 512> buffer{};
  for (ssize_t n; (n = ::read(fds[0], buffer.data(), buffer.size())) > 0;)
    out.append(buffer.data(), n);
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return out;
}

TEST(Realtime, TheUnitsRtprioLimitAllowsFifoUpToItWithoutCapabilities) {
  if (::geteuid() != 0) {
    GTEST_SKIP() << "needs root to drop to user nobody with RLIMIT_RTPRIO 50 (navd.service's "
                    "LimitRTPRIO=50); the refusal path is checked below";
  }
  const std::string root = on_a_thread([] { return request_fifo_priority(10); });
  if (!root.empty()) {
    GTEST_SKIP() << "the kernel refuses SCHED_FIFO to root itself here (" << root
                 << "): a container without CAP_SYS_NICE or without real-time group runtime";
  }
  // Above the limit refused, at 40 granted: navd's rov.yaml priorities are <= 50.
  const std::string out = as_unprivileged_user(50, {60, 40});
  if (out == kCannotSetLimit) {
    GTEST_SKIP() << "RLIMIT_RTPRIO's hard limit is below 50 here and root lacks "
                    "CAP_SYS_RESOURCE to raise it: the unprivileged grant is not checked";
  }
  EXPECT_EQ(out,
            "SCHED_FIFO priority 60: Operation not permitted (RLIMIT_RTPRIO is 50 and the process "
            "lacks CAP_SYS_NICE; navd.service's LimitRTPRIO= raises the limit)=SCHED_OTHER|"
            "=SCHED_FIFO 40|");
}

TEST(Realtime, WithoutTheLimitTheRefusalNamesIt) {
  if (::geteuid() == 0) {
    const std::string out = as_unprivileged_user(0, {1, 1});
    EXPECT_EQ(out.substr(0, out.find('|')),
              "SCHED_FIFO priority 1: Operation not permitted (RLIMIT_RTPRIO is 0 and the process "
              "lacks CAP_SYS_NICE; navd.service's LimitRTPRIO= raises the limit)=SCHED_OTHER");
    return;
  }
  rlimit rl{};
  ASSERT_EQ(::getrlimit(RLIMIT_RTPRIO, &rl), 0);
  if (rl.rlim_cur != 0) GTEST_SKIP() << "this user's RLIMIT_RTPRIO is not 0";
  const std::string out = on_a_thread([] { return request_fifo_priority(1); });
  EXPECT_NE(out.find("RLIMIT_RTPRIO is 0"), std::string::npos) << out;
}

TEST(Realtime, TheTallyCountsGrantsAndRefusals) {
  RealtimeTally tally;
  on_a_thread([&] {
    tally.enter("out of range", 100);
    tally.enter("normal", 0);
    return std::string();
  });
  EXPECT_EQ(tally.granted(), 0);
  EXPECT_EQ(tally.refused(), 1);
  const std::string granted = on_a_thread([] { return request_fifo_priority(5); });
  on_a_thread([&] {
    tally.enter("allowed", 5);
    return std::string();
  });
  EXPECT_EQ(tally.granted(), granted.empty() ? 1 : 0) << granted;
  EXPECT_EQ(tally.refused(), granted.empty() ? 1 : 2) << granted;
}

/// In a forked child (malloc settings are per process): with or without keep_freed_memory, a
/// 64 MiB block allocated, then freed. Exit code bit 0: the block was mmapped (mallinfo2's
/// hblkhd); bit 1: the heap still held it after free (arena); bit 2: a setting was refused.
int large_block_fate(bool keep) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    int code = keep && !keep_freed_memory() ? 4 : 0;
    constexpr std::size_t kBytes = 64u << 20;
    static void* volatile block;  // volatile: the allocation is not elided
    block = std::malloc(kBytes);
    std::memset(block, 1, kBytes);
    if (::mallinfo2().hblkhd >= kBytes) code |= 1;
    std::free(block);
    if (::mallinfo2().arena >= kBytes) code |= 2;
    ::_exit(code);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(Realtime, KeepFreedMemoryServesLargeBlocksFromTheHeapAndKeepsThem) {
  EXPECT_EQ(large_block_fate(false), 1);  // glibc's default: mmapped, unmapped at free
  EXPECT_EQ(large_block_fate(true), 2);   // from the heap, kept for the next allocation
}

TEST(Realtime, LockingMemoryLocksItOrSaysWhyNot) {
  // In a child: mlockall(MCL_FUTURE) would stay in force for the rest of this test binary.
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string why = lock_all_memory();
    std::ostringstream status;
    status << std::ifstream("/proc/self/status").rdbuf();
    const double locked_kb = parse_proc_status_kb(status.str(), "VmLck").value_or(0.0);
    // 0: locked with pages counted; 2: refused with RLIMIT_MEMLOCK named; else failure.
    if (why.empty()) ::_exit(locked_kb > 0 ? 0 : 1);
    ::_exit(why.find("RLIMIT_MEMLOCK") != std::string::npos ? 2 : 3);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  if (WEXITSTATUS(status) == 2) GTEST_SKIP() << "mlockall refused here (RLIMIT_MEMLOCK named)";
  EXPECT_EQ(WEXITSTATUS(status), 0) << "1: locked but VmLck is 0; 3: refused without a reason";
}

}  // namespace
}  // namespace nav::daemon
