// SerialPort end to end over pseudo-terminals (openpty(3)): termios configuration, data both
// ways, arbitrary chunking, timeouts, exclusive open, and a device that vanishes mid-stream and
// comes back under the same path (a symlink re-pointed to a new pty, as udev does for
// /dev/serial/by-id links when a USB-serial adapter is re-plugged).

#include "nav/drivers/transports/serial_port.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace nav::drivers {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

/// One pseudo-terminal pair; the test plays the sensor on the master side.
class Pty {
 public:
  Pty() {
    char name[256] = {};
    int slave = -1;
    if (::openpty(&master_, &slave, name, nullptr, nullptr) != 0) return;
    slave_path_ = name;
    ::close(slave);  // SerialPort opens the slave by path
  }
  ~Pty() { close_master(); }
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;
  bool ok() const { return master_ >= 0; }
  const std::string& slave_path() const { return slave_path_; }
  void close_master() {
    if (master_ >= 0) ::close(master_);
    master_ = -1;
  }
  void send(const std::string& bytes) const {
    ASSERT_EQ(::write(master_, bytes.data(), bytes.size()), static_cast<ssize_t>(bytes.size()));
  }
  /// Reads what the port wrote, waiting up to `timeout` for `n` bytes.
  std::string receive(std::size_t n, std::chrono::milliseconds timeout) const {
    std::string out;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (out.size() < n && std::chrono::steady_clock::now() < deadline) {
      pollfd pfd{master_, POLLIN, 0};
      if (::poll(&pfd, 1, 20) <= 0) continue;
      char buf[256];
      const ssize_t got = ::read(master_, buf, sizeof buf);
      if (got > 0) out.append(buf, static_cast<std::size_t>(got));
    }
    return out;
  }

 private:
  int master_ = -1;
  std::string slave_path_;
};

SerialOptions options_for(const std::string& device) {
  SerialOptions o;
  o.device = device;
  o.baud = 115200;
  o.reconnect_initial = 10ms;
  o.reconnect_max = 40ms;
  return o;
}

/// Reads until `n` bytes arrived or `timeout` passed; stops at the first non-timeout error.
std::string read_n(SerialPort& port, std::size_t n, std::chrono::milliseconds timeout,
                   IoStatus* last_error = nullptr) {
  std::string out;
  std::vector<uint8_t> buf(64);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (out.size() < n && std::chrono::steady_clock::now() < deadline) {
    ReadResult r = port.read(buf, 20ms);
    if (r.status.ok()) {
      EXPECT_GT(r.received.monotonic_us, 0);
      out.append(reinterpret_cast<const char*>(buf.data()), r.bytes);
    } else if (r.status.code() != IoCode::kTimeout) {
      if (last_error != nullptr) *last_error = r.status;
      break;
    }
  }
  return out;
}

TEST(SerialOptions, ValidateNamesTheBadField) {
  SerialOptions o = options_for("/dev/ttyS0");
  EXPECT_TRUE(o.validate().ok());
  o.baud = 12345;
  EXPECT_NE(o.validate().message().find("baud 12345"), std::string::npos);
  o = options_for("/dev/ttyS0");
  o.data_bits = 9;
  EXPECT_NE(o.validate().message().find("data_bits"), std::string::npos);
  o = options_for("/dev/ttyS0");
  o.stop_bits = 3;
  EXPECT_EQ(o.validate().code(), IoCode::kInvalidArgument);
  o = options_for("");
  EXPECT_NE(o.validate().message().find("device"), std::string::npos);
  o = options_for("/dev/ttyS0");
  o.reconnect_max = 1ms;
  EXPECT_FALSE(o.validate().ok());
}

TEST(SerialPort, InvalidOptionsFailEveryCallWithTheReason) {
  SerialOptions o = options_for("/dev/null");
  o.baud = 7;
  SerialPort port(o);
  EXPECT_EQ(port.open().code(), IoCode::kInvalidArgument);
  std::vector<uint8_t> buf(8);
  EXPECT_NE(port.read(buf, 1ms).status.message().find("baud 7"), std::string::npos);
  EXPECT_FALSE(port.is_open());
}

TEST(SerialPort, OpeningANonTtyFailsWithDeviceAndErrno) {
  SerialPort port(options_for("/dev/null"));
  const IoStatus s = port.open();
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.errno_value(), ENOTTY);
  EXPECT_NE(s.message().find("/dev/null"), std::string::npos);
  EXPECT_FALSE(port.is_open());
}

TEST(SerialPort, ConfiguresRawModeWithRequestedFraming) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialOptions o = options_for(pty.slave_path());
  o.baud = 19200;
  o.stop_bits = 2;
  o.flow_control = FlowControl::kHardware;
  SerialPort port(o);
  const IoStatus opened = port.open();
  ASSERT_TRUE(opened.ok()) << opened.message();
  termios tio{};
  ASSERT_EQ(::tcgetattr(port.native_handle(), &tio), 0);
  EXPECT_EQ(cfgetispeed(&tio), static_cast<speed_t>(B19200));
  EXPECT_EQ(cfgetospeed(&tio), static_cast<speed_t>(B19200));
  EXPECT_EQ(tio.c_cflag & CSIZE, static_cast<tcflag_t>(CS8));
  EXPECT_EQ(tio.c_cflag & PARENB, 0u);
  EXPECT_NE(tio.c_cflag & CSTOPB, 0u);
  EXPECT_NE(tio.c_cflag & CRTSCTS, 0u);
  EXPECT_EQ(tio.c_lflag & (ICANON | ECHO | ISIG), 0u);
  EXPECT_EQ(tio.c_iflag & (ICRNL | IXON), 0u);
  EXPECT_EQ(tio.c_oflag & OPOST, 0u);
}

TEST(SerialPort, FramingTheDeviceRefusesIsReportedNotIgnored) {
  // A Linux pty forces CS8 without parity: asking for 7E1 must fail loudly, not run at 8N1.
  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialOptions o = options_for(pty.slave_path());
  o.data_bits = 7;
  o.parity = Parity::kEven;
  SerialPort port(o);
  const IoStatus s = port.open();
  EXPECT_EQ(s.code(), IoCode::kUnsupported);
  EXPECT_NE(s.message().find("parity"), std::string::npos);
  EXPECT_FALSE(port.is_open());
}

TEST(SerialPort, CarriesDataBothWaysUntranslated) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialPort port(options_for(pty.slave_path()));
  ASSERT_TRUE(port.open().ok());
  // CR, LF, XON/XOFF, ^C and 0xFF must pass untouched in raw mode.
  const std::string sensor_bytes =
      std::string("$HEHDT,123.4,T*2F\r\n") + '\x11' + '\x13' + '\x03' + '\xff' + '\0';
  pty.send(sensor_bytes);
  EXPECT_EQ(read_n(port, sensor_bytes.size(), 2s), sensor_bytes);

  const std::string command = "*0100P3\r\n";  // a Paroscientific poll command
  ASSERT_TRUE(
      port.write({reinterpret_cast<const uint8_t*>(command.data()), command.size()}, 1s).ok());
  EXPECT_EQ(pty.receive(command.size(), 2s), command);
  EXPECT_EQ(port.stats().bytes_written, command.size());
  EXPECT_EQ(port.read({}, 1ms).status.code(), IoCode::kInvalidArgument);  // not a hang-up
  EXPECT_TRUE(port.is_open());
  EXPECT_EQ(port.stats().bytes_read, sensor_bytes.size());
}

TEST(SerialPort, ReassemblesArbitrarilyChunkedInput) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialPort port(options_for(pty.slave_path()));
  ASSERT_TRUE(port.open().ok());
  std::mt19937 rng(42);
  std::string all;
  for (int i = 0; i < 3000; ++i) all.push_back(static_cast<char>(rng() & 0xff));
  std::size_t pos = 0;
  std::string received;
  while (pos < all.size()) {
    const std::size_t n = std::min<std::size_t>(1 + rng() % 97, all.size() - pos);
    pty.send(all.substr(pos, n));
    pos += n;
    received += read_n(port, n, 2s);  // keep the pty buffer from filling
  }
  EXPECT_EQ(received, all);
}

TEST(SerialPort, ReadTimesOutWhenTheSensorIsSilent) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialPort port(options_for(pty.slave_path()));
  ASSERT_TRUE(port.open().ok());
  std::vector<uint8_t> buf(16);
  const auto t0 = std::chrono::steady_clock::now();
  const ReadResult r = port.read(buf, 60ms);
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 55ms);
  EXPECT_EQ(r.status.code(), IoCode::kTimeout);
  EXPECT_EQ(r.bytes, 0u);
  EXPECT_TRUE(port.is_open());
}

TEST(SerialPort, ExclusiveOpenRefusesASecondOpener) {
  Pty pty;
  ASSERT_TRUE(pty.ok());
  SerialPort first(options_for(pty.slave_path()));
  ASSERT_TRUE(first.open().ok());
  SerialPort second(options_for(pty.slave_path()));
  const IoStatus s = second.open();
  EXPECT_EQ(s.code(), IoCode::kBusy) << s.message();
  first.close();
  EXPECT_TRUE(second.open().ok());
}

TEST(SerialPort, DeviceVanishingMidStreamIsReportedAndReconnects) {
  const fs::path link = fs::temp_directory_path() / ("navd_serial_" + std::to_string(::getpid()));
  fs::remove(link);
  auto first = std::make_unique<Pty>();
  ASSERT_TRUE(first->ok());
  fs::create_symlink(first->slave_path(), link);
  SerialPort port(options_for(link.string()));
  ASSERT_TRUE(port.open().ok());
  first->send("before-");
  EXPECT_EQ(read_n(port, 7, 2s), "before-");

  first->close_master();  // the adapter is unplugged mid-stream
  IoStatus error;
  read_n(port, 1, 2s, &error);
  EXPECT_EQ(error.code(), IoCode::kDisconnected) << error.message();
  EXPECT_NE(error.message().find(link.string()), std::string::npos);
  EXPECT_FALSE(port.is_open());
  EXPECT_EQ(port.stats().disconnects, 1u);

  fs::remove(link);  // while absent, reads keep failing cleanly (no crash, no data)
  std::vector<uint8_t> buf(16);
  for (int i = 0; i < 3; ++i) {
    const ReadResult r = port.read(buf, 30ms);
    EXPECT_EQ(r.status.code(), IoCode::kDisconnected) << r.status.message();
  }
  EXPECT_GE(port.stats().open_failures, 1u);

  Pty second;  // re-plugged: same path, new device node
  ASSERT_TRUE(second.ok());
  fs::create_symlink(second.slave_path(), link);
  std::string resumed;
  const auto deadline = std::chrono::steady_clock::now() + 3s;
  while (!port.is_open() && std::chrono::steady_clock::now() < deadline) (void)port.read(buf, 20ms);
  ASSERT_TRUE(port.is_open());
  second.send("after");
  EXPECT_EQ(read_n(port, 5, 2s), "after");
  EXPECT_EQ(port.stats().reconnects, 1u);
  fs::remove(link);
}

TEST(MemoryByteStream, ReplaysChunksErrorsAndRecordsWrites) {
  MemoryByteStream stream("replay");
  const std::vector<uint8_t> a{1, 2, 3, 4, 5};
  stream.push(a, HostTime{10, 20});
  stream.push_error(IoStatus::Error(IoCode::kDisconnected, "replay", "unplugged"));
  std::vector<uint8_t> buf(3);
  ReadResult r = stream.read(buf, 0ms);
  ASSERT_TRUE(r.status.ok());
  EXPECT_EQ(r.bytes, 3u);
  EXPECT_EQ(r.received.monotonic_us, 10);
  r = stream.read(buf, 0ms);  // rest of the same chunk, never joined with the next item
  EXPECT_EQ(r.bytes, 2u);
  EXPECT_EQ(buf[0], 4);
  EXPECT_EQ(stream.read(buf, 0ms).status.code(), IoCode::kDisconnected);
  EXPECT_EQ(stream.read(buf, 1ms).status.code(), IoCode::kTimeout);
  ASSERT_TRUE(stream.write(a, 0ms).ok());
  EXPECT_EQ(stream.written(), a);
}

}  // namespace
}  // namespace nav::drivers
