// sd_notify wrapper: the exact datagrams arrive on a NOTIFY_SOCKET owned by the test (an AF_UNIX
// datagram socket in a temp dir); watchdog interval from WATCHDOG_USEC / WATCHDOG_PID.
#include "nav/daemon/system/sd_notify.h"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

namespace nav::daemon {
namespace {

class SdNotify : public ::testing::Test {
 protected:
  void SetUp() override {
    char dir_template[] = "/tmp/navd-sdnotify-XXXXXX";
    ASSERT_NE(mkdtemp(dir_template), nullptr) << std::strerror(errno);
    dir_ = dir_template;
    path_ = dir_ + "/notify";
    fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    ASSERT_GE(fd_, 0) << std::strerror(errno);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::strncpy(addr.sun_path, path_.c_str(), sizeof(addr.sun_path) - 1);
    ASSERT_EQ(bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0)
        << std::strerror(errno);
    timeval timeout{2, 0};  // a missing datagram fails the test instead of hanging it
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
    setenv("NOTIFY_SOCKET", path_.c_str(), 1);
    unsetenv("WATCHDOG_USEC");
    unsetenv("WATCHDOG_PID");
  }
  void TearDown() override {
    unsetenv("NOTIFY_SOCKET");
    unsetenv("WATCHDOG_USEC");
    unsetenv("WATCHDOG_PID");
    if (fd_ >= 0) close(fd_);
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  /// Next datagram's text, or "<timeout>".
  std::string receive() {
    char buffer[4096];
    const ssize_t n = recv(fd_, buffer, sizeof(buffer), 0);
    return n < 0 ? std::string("<timeout>") : std::string(buffer, static_cast<std::size_t>(n));
  }
  bool nothing_pending() {
    char byte;
    return recv(fd_, &byte, 1, MSG_DONTWAIT) < 0;
  }

  std::string dir_, path_;
  int fd_ = -1;
};

TEST_F(SdNotify, SendsTheExactMessages) {
  const SdNotifier notifier;
  ASSERT_TRUE(notifier.enabled());
  EXPECT_TRUE(notifier.ready());
  EXPECT_EQ(receive(), "READY=1");
  EXPECT_TRUE(notifier.watchdog());
  EXPECT_EQ(receive(), "WATCHDOG=1");
  EXPECT_TRUE(notifier.status("filter ok, 3/5 sensors, 12 states"));
  EXPECT_EQ(receive(), "STATUS=filter ok, 3/5 sensors, 12 states");
  EXPECT_TRUE(notifier.ready_with_status("running"));
  EXPECT_EQ(receive(), "READY=1\nSTATUS=running");
  EXPECT_TRUE(notifier.stopping());
  EXPECT_EQ(receive(), "STOPPING=1");
  EXPECT_TRUE(nothing_pending());
}

TEST_F(SdNotify, StatusIsOneLine) {
  const SdNotifier notifier;
  EXPECT_TRUE(notifier.status("dvl lost\nWATCHDOG=1"));  // no injected assignment
  EXPECT_EQ(receive(), "STATUS=dvl lost WATCHDOG=1");
  EXPECT_EQ(sanitize_status_line("a\tb\rc\x7f"), "a b c ");
}

TEST_F(SdNotify, WatchdogIntervalFromEnvironment) {
  setenv("WATCHDOG_USEC", "3000000", 1);
  setenv("WATCHDOG_PID", std::to_string(getpid()).c_str(), 1);
  const SdNotifier notifier;
  ASSERT_TRUE(notifier.watchdog_timeout().has_value());
  EXPECT_EQ(notifier.watchdog_timeout()->count(), 3'000'000);
  EXPECT_EQ(notifier.watchdog_period()->count(), 1'500'000);
  // The environment stays for children / later readers.
  EXPECT_NE(std::getenv("WATCHDOG_USEC"), nullptr);
}

TEST_F(SdNotify, WatchdogForAnotherProcessIsIgnored) {
  setenv("WATCHDOG_USEC", "3000000", 1);
  setenv("WATCHDOG_PID", std::to_string(getpid() + 1).c_str(), 1);
  const SdNotifier notifier;
  EXPECT_FALSE(notifier.watchdog_timeout().has_value());
  EXPECT_FALSE(notifier.watchdog_period().has_value());
}

TEST_F(SdNotify, NoWatchdogWithoutWatchdogUsec) {
  const SdNotifier notifier;
  EXPECT_FALSE(notifier.watchdog_timeout().has_value());
}

TEST_F(SdNotify, DisabledOutsideSystemd) {
  unsetenv("NOTIFY_SOCKET");
  const SdNotifier notifier;
  EXPECT_FALSE(notifier.enabled());
  EXPECT_FALSE(notifier.ready());
  EXPECT_FALSE(notifier.watchdog());
  EXPECT_TRUE(nothing_pending());
}

TEST_F(SdNotify, SendFailureIsReported) {
  setenv("NOTIFY_SOCKET", (dir_ + "/nobody-listens").c_str(), 1);
  const SdNotifier notifier;
  EXPECT_TRUE(notifier.enabled());
  EXPECT_FALSE(notifier.ready());
}

}  // namespace
}  // namespace nav::daemon
