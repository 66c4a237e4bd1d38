// SerialPort against a virtual null-modem made by socat in a separate process
// (`socat pty,raw,echo=0,link=A pty,raw,echo=0,link=B`): the test plays the sensor on B. Killing
// socat makes the device vanish mid-stream exactly as an unplugged USB adapter does (hang-up,
// link removed); starting it again brings the same path back, and the port must reconnect.
// Skips with the reason when socat is not installed.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "nav/drivers/transports/serial_port.h"
#include "nav/testing/child_process.h"

namespace nav::drivers {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

/// socat null-modem between two pty links; stopped (by its pid) in the destructor.
class SocatNullModem {
 public:
  SocatNullModem(fs::path port_link, fs::path sensor_link)
      : port_link_(std::move(port_link)), sensor_link_(std::move(sensor_link)) {}
  ~SocatNullModem() { stop(); }

  /// Starts socat and waits until both links exist; false if it did not come up.
  bool start() {
    const std::string a = "pty,raw,echo=0,link=" + port_link_.string();
    const std::string b = "pty,raw,echo=0,link=" + sensor_link_.string();
    pid_ = ::fork();
    if (pid_ == 0) {
      ::execlp("socat", "socat", a.c_str(), b.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    for (int i = 0; i < 200; ++i) {
      if (fs::exists(port_link_) && fs::exists(sensor_link_)) return true;
      if (::waitpid(pid_, nullptr, WNOHANG) == pid_) {
        pid_ = -1;
        return false;
      }
      std::this_thread::sleep_for(10ms);
    }
    return false;
  }
  /// Stops socat (SIGKILL if it ignores SIGTERM) and removes the links it would have removed.
  void stop() {
    if (pid_ <= 0) return;
    (void)nav::testing::terminate_child(pid_);
    pid_ = -1;
    std::error_code ignored;
    fs::remove(port_link_, ignored);
    fs::remove(sensor_link_, ignored);
  }

 private:
  fs::path port_link_;
  fs::path sensor_link_;
  pid_t pid_ = -1;
};

/// The sensor's end of the null-modem, raw.
class SensorEnd {
 public:
  explicit SensorEnd(const fs::path& link) : fd_(::open(link.c_str(), O_RDWR | O_NOCTTY)) {
    termios tio{};
    if (fd_ >= 0 && ::tcgetattr(fd_, &tio) == 0) {
      cfmakeraw(&tio);
      ::tcsetattr(fd_, TCSANOW, &tio);
    }
  }
  ~SensorEnd() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool ok() const { return fd_ >= 0; }
  void send(const std::string& s) const {
    ASSERT_EQ(::write(fd_, s.data(), s.size()), static_cast<ssize_t>(s.size()));
  }
  std::string receive(std::size_t n) const {
    std::string out;
    for (int i = 0; i < 100 && out.size() < n; ++i) {
      pollfd pfd{fd_, POLLIN, 0};
      if (::poll(&pfd, 1, 20) <= 0) continue;
      char buf[128];
      const ssize_t got = ::read(fd_, buf, sizeof buf);
      if (got > 0) out.append(buf, static_cast<std::size_t>(got));
    }
    return out;
  }

 private:
  int fd_;
};

std::string read_until(SerialPort& port, std::size_t n, IoStatus* error) {
  std::string out;
  std::vector<uint8_t> buf(64);
  const auto deadline = std::chrono::steady_clock::now() + 3s;
  while (out.size() < n && std::chrono::steady_clock::now() < deadline) {
    const ReadResult r = port.read(buf, 20ms);
    if (r.status.ok()) {
      out.append(reinterpret_cast<const char*>(buf.data()), r.bytes);
    } else if (r.status.code() != IoCode::kTimeout) {
      if (error != nullptr) *error = r.status;
      if (r.status.code() != IoCode::kDisconnected || error != nullptr) break;
    }
  }
  return out;
}

TEST(SerialSocat, SensorUnpluggedAndReplugged) {
  const fs::path dir = fs::temp_directory_path();
  const std::string tag = std::to_string(::getpid());
  const fs::path port_link = dir / ("navd_socat_port_" + tag);
  const fs::path sensor_link = dir / ("navd_socat_sensor_" + tag);
  SocatNullModem modem(port_link, sensor_link);
  if (!modem.start()) GTEST_SKIP() << "socat is not installed or could not create ptys";

  SerialOptions o;
  o.device = port_link.string();
  o.baud = 115200;
  o.reconnect_initial = 10ms;
  o.reconnect_max = 50ms;
  SerialPort port(o);
  ASSERT_TRUE(port.open().ok());
  {
    SensorEnd sensor(sensor_link);
    ASSERT_TRUE(sensor.ok());
    sensor.send("$HEHDT,271.5,T*2A\r\n");
    EXPECT_EQ(read_until(port, 19, nullptr), "$HEHDT,271.5,T*2A\r\n");
    const std::string poll = "*0100P3\r\n";
    ASSERT_TRUE(port.write({reinterpret_cast<const uint8_t*>(poll.data()), poll.size()}, 1s).ok());
    EXPECT_EQ(sensor.receive(poll.size()), poll);
  }

  modem.stop();  // unplugged mid-stream
  IoStatus error;
  read_until(port, 1, &error);
  EXPECT_EQ(error.code(), IoCode::kDisconnected) << error.message();
  EXPECT_EQ(port.stats().disconnects, 1u);

  ASSERT_TRUE(modem.start());  // plugged in again: same path, new pty
  SensorEnd sensor(sensor_link);
  ASSERT_TRUE(sensor.ok());
  std::vector<uint8_t> buf(8);
  const auto deadline = std::chrono::steady_clock::now() + 3s;
  while (!port.is_open() && std::chrono::steady_clock::now() < deadline) (void)port.read(buf, 20ms);
  ASSERT_TRUE(port.is_open());
  sensor.send("resumed");
  EXPECT_EQ(read_until(port, 7, nullptr), "resumed");
  EXPECT_EQ(port.stats().reconnects, 1u);
}

}  // namespace
}  // namespace nav::drivers
