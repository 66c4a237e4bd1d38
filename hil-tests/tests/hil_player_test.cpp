// DivePlayer on a hand-made dive (hil-tests/README.md "Playing a dive back"): a heading and a
// depth sensor on ptys, a CAN DVL and a camera. Each pty must carry exactly its sensor's
// recorded bytes in order; the CAN DVL's frames go onto vcan0 where the kernel has it (checked
// by a listener there; the test skips with the reason where the kernel has no CAN), else the
// sensor is not played and its note says why; the written
// navd config must load and point each transport at what the player writes; without a reader the
// player gives up and plays nothing.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <stdio.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "nav/daemon/config/config.h"
#include "nav/daemon/log/dive_log.h"
#include "nav/drivers/transports/can_bus.h"
#include "nav/hil/dive_player.h"
#include "support/sim_dive.h"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

constexpr std::int64_t kStartMonotonicUs = 1'000'000'000;
constexpr std::int64_t kStartRealtimeUs = 1'086'048'000'000'000;

const char* kConfig = R"(sensors:
  - name: heading
    type: heading_nmea
    transport: {type: sim}
  - name: depth
    type: pressure_paro
    transport: {type: serial, device: /dev/ttyUSB3, baud: 9600}
  - name: dvl_can
    type: dvl_can
    transport: {type: can, interface: can0, signals_file: dvl_fog.yaml}
  - name: camera
    type: camera_gige
    transport: {type: sim}
    camera: {fx: 1000.0, fy: 1000.0, cx: 640.0, cy: 512.0, pixel_format: mono12}
sim: {dive_dir: somewhere}
)";

struct HandMadeDive {
  fs::path dir;
  std::string heading_bytes, depth_bytes;
  int can_lines = 0;
};

void write_raw(nav::daemon::DiveLogWriter& log, const std::string& sensor, int i,
               const std::string& bytes) {
  const std::int64_t dt_us = 10'000LL * i;
  log.write_raw(sensor, kStartRealtimeUs + dt_us, kStartMonotonicUs + dt_us,
                {reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()});
}

/// 40 events 10 ms apart: heading lines, depth replies, CAN lines, one unknown sensor.
HandMadeDive make_dive(const fs::path& dir) {
  HandMadeDive d{dir, {}, {}, 0};
  std::ofstream(dir / "config.yaml") << kConfig;
  fs::copy_file(fs::path(NAV_SOURCE_DIR) / "config" / "can" / "dvl_fog_example.yaml",
                dir / "dvl_fog.yaml");
  nav::daemon::DiveLogWriter log((dir / "dive.lcmlog").string());
  for (int i = 0; i < 40; ++i) {
    if (i % 4 == 3) {
      write_raw(log, "dvl_can", i, "(1086048000.0" + std::to_string(10 + i) + ") can0 201#0102\n");
      ++d.can_lines;
    } else if (i % 4 == 1) {
      const std::string reply = "*00012" + std::to_string(9000 + i) + ".3918\r\n";
      write_raw(log, "depth", i, reply);
      d.depth_bytes += reply;
    } else {
      const std::string line = "$HEHDT," + std::to_string(40 + i) + ".87,T*25\r\n";
      write_raw(log, "heading", i, line);
      d.heading_bytes += line;
    }
  }
  write_raw(log, "ghost", 40, "?");
  return d;
}

/// Opens `link` like a serial driver (raw mode) and reads `expected` bytes or until 5 s.
std::string read_pty(const fs::path& link, std::size_t expected) {
  const int fd = ::open(link.c_str(), O_RDWR | O_NOCTTY);
  if (fd < 0) return "open failed";
  termios t{};
  ::tcgetattr(fd, &t);
  ::cfmakeraw(&t);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 1;
  ::tcsetattr(fd, TCSANOW, &t);
  std::string got;
  const auto until = std::chrono::steady_clock::now() + 5s;
  char buf[256];
  while (got.size() < expected && std::chrono::steady_clock::now() < until) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) got.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return got;
}

const nav::hil::PlayedSensor& sensor(const std::vector<nav::hil::PlayedSensor>& all,
                                     const std::string& name) {
  for (const auto& s : all) {
    if (s.name == name) return s;
  }
  throw std::runtime_error("no sensor " + name);
}

TEST(HilPlayer, EachPtyCarriesItsSensorsBytesInOrder) {
  const fs::path dir = nav::sim::test::scratch_dir("hil_player_bytes");
  const HandMadeDive dive = make_dive(dir);
  nav::hil::PlayerOptions o;
  o.speed = 10.0;
  o.serial_dir = dir / "tty";
  o.reader_timeout = 5s;
  o.fake_gige_camera = false;
  nav::hil::DivePlayer player(dir, o);
  const bool can = sensor(player.sensors(), "dvl_can").output == nav::hil::SensorOutput::kCan;

  std::string heading, depth;
  std::thread heading_reader(
      [&] { heading = read_pty(dir / "tty" / "heading", dive.heading_bytes.size()); });
  std::thread depth_reader(
      [&] { depth = read_pty(dir / "tty" / "depth", dive.depth_bytes.size()); });
  const std::atomic<bool> stop{false};
  const nav::hil::PlayReport r = player.play(stop);
  heading_reader.join();
  depth_reader.join();

  ASSERT_TRUE(r.started);
  EXPECT_FALSE(r.stopped);
  EXPECT_EQ(heading, dive.heading_bytes);
  EXPECT_EQ(depth, dive.depth_bytes);
  EXPECT_EQ(sensor(r.sensors, "heading").messages, 20);
  EXPECT_EQ(sensor(r.sensors, "depth").messages, 10);
  EXPECT_EQ(sensor(r.sensors, "heading").dropped_bytes, 0);
  EXPECT_EQ(r.raw_unknown_sensor, 1);
  // First message (0) to the last one written: the CAN line 39, else the heading line 38.
  EXPECT_NEAR(r.dive_span_s, can ? 0.39 : 0.38, 1e-9);
  EXPECT_EQ(sensor(r.sensors, "camera").output, nav::hil::SensorOutput::kNotPlayed);
  const nav::hil::PlayedSensor& c = sensor(r.sensors, "dvl_can");
  if (!can) {  // the kernel has no vcan0: skipped with the reason, nothing sent
    EXPECT_EQ(c.output, nav::hil::SensorOutput::kNotPlayed);
    EXPECT_NE(c.note.find("vcan0"), std::string::npos) << c.note;
    EXPECT_EQ(c.messages, 0);
  }
}

TEST(HilPlayer, CanFramesReachVcan0) {
  const fs::path dir = nav::sim::test::scratch_dir("hil_player_can");
  const HandMadeDive dive = make_dive(dir);
  nav::hil::PlayerOptions o;
  o.speed = 10.0;
  o.wait_for_readers = false;  // the ptys are not read here
  o.fake_gige_camera = false;
  nav::hil::DivePlayer player(dir, o);
  const nav::hil::PlayedSensor& planned = sensor(player.sensors(), "dvl_can");
  if (planned.output != nav::hil::SensorOutput::kCan) GTEST_SKIP() << planned.note;
  nav::drivers::SocketCanBus listener;
  ASSERT_TRUE(listener.open_interface("vcan0").ok());
  const std::atomic<bool> stop{false};
  const nav::hil::PlayReport r = player.play(stop);
  EXPECT_EQ(sensor(r.sensors, "dvl_can").messages, dive.can_lines);
  EXPECT_EQ(sensor(r.sensors, "dvl_can").dropped_frames, 0);
  int frames = 0;
  nav::drivers::CanFrame f;
  while (listener.receive(f, 200ms).ok()) {
    EXPECT_EQ(f.id, 0x201u);
    ++frames;
  }
  EXPECT_EQ(frames, dive.can_lines);
}

TEST(HilPlayer, WritesANavdConfigPointingAtThePlayedDevices) {
  const fs::path dir = nav::sim::test::scratch_dir("hil_player_config");
  make_dive(dir);
  nav::hil::PlayerOptions o;
  o.fake_gige_camera = false;
  nav::hil::DivePlayer player(dir / "dive.lcmlog", o);
  EXPECT_EQ(player.serial_dir(), dir / "hil");
  player.write_navd_config(dir / "navd.yaml", "memq://");
  const nav::daemon::NavdConfig c = nav::daemon::load_config_file((dir / "navd.yaml").string());
  ASSERT_EQ(c.sensors.size(), 4u);
  const auto* heading = std::get_if<nav::daemon::SerialTransport>(&c.sensors[0].transport);
  const auto* depth = std::get_if<nav::daemon::SerialTransport>(&c.sensors[1].transport);
  ASSERT_TRUE(heading && depth);
  EXPECT_EQ(heading->device, (dir / "hil" / "heading").string());
  EXPECT_EQ(heading->baud, 115200);
  EXPECT_EQ(depth->device, (dir / "hil" / "depth").string());
  EXPECT_EQ(depth->baud, 9600);  // the recorded serial settings are kept
  EXPECT_TRUE(fs::is_symlink(depth->device));
  if (const auto* can = std::get_if<nav::daemon::CanTransport>(&c.sensors[2].transport)) {
    EXPECT_EQ(can->interface, "vcan0");
    EXPECT_EQ(can->signals_file, (dir / "dvl_fog.yaml").string());
  } else {
    EXPECT_TRUE(std::holds_alternative<nav::daemon::SimTransport>(c.sensors[2].transport));
  }
  EXPECT_TRUE(std::holds_alternative<nav::daemon::SimTransport>(c.sensors[3].transport));
  EXPECT_EQ(c.lcm.url, "memq://");
  EXPECT_FALSE(c.sim.has_value());
}

TEST(HilPlayer, WithoutAReaderGivesUpAndPlaysNothing) {
  const fs::path dir = nav::sim::test::scratch_dir("hil_player_no_reader");
  make_dive(dir);
  nav::hil::PlayerOptions o;
  o.reader_timeout = 200ms;
  o.fake_gige_camera = false;
  nav::hil::DivePlayer player(dir, o);
  const std::atomic<bool> stop{false};
  const nav::hil::PlayReport r = player.play(stop);
  EXPECT_FALSE(r.started);
  EXPECT_EQ(sensor(r.sensors, "heading").messages, 0);
}

TEST(HilPlayer, RejectsBadOptionsAndMissingFiles) {
  const fs::path dir = nav::sim::test::scratch_dir("hil_player_bad");
  nav::hil::PlayerOptions o;
  o.speed = 0.0;
  EXPECT_EQ(o.validate(), "speed 0.000000 is not in (0, 1000]");
  try {
    nav::hil::DivePlayer player(dir, nav::hil::PlayerOptions{});
    ADD_FAILURE() << "no dive log, no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("dive.lcmlog: no such dive log"), std::string::npos)
        << e.what();
  }
}

TEST(HilPlayer, NavtoolHilPlayWritesTheConfigAndReportsJson) {
  const fs::path dir = nav::sim::test::scratch_dir("hil_player_navtool");
  make_dive(dir);
  const std::string cmd = std::string(NAVTOOL_PATH) + " hil-play " + dir.string() +
                          " --speed 100 --no-wait --no-camera --json --lcm-url memq:// 2>" +
                          (dir / "stderr").string();
  FILE* pipe = ::popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, pipe)) out += buf;
  ASSERT_EQ(::pclose(pipe), 0) << nav::sim::test::file_text(dir / "stderr");
  const nlohmann::json j = nlohmann::json::parse(out);
  EXPECT_TRUE(j["started"].get<bool>());
  ASSERT_EQ(j["sensors"].size(), 4u);
  EXPECT_EQ(j["sensors"][0]["name"], "heading");
  EXPECT_EQ(j["sensors"][0]["output"], "pty");
  EXPECT_EQ(j["sensors"][0]["messages"].get<int>(), 20);  // written; no reader: bytes dropped
  EXPECT_EQ(j["sensors"][3]["output"], "not_played");
  EXPECT_EQ(j["raw_unknown_sensor"].get<int>(), 1);
  const std::string err = nav::sim::test::file_text(dir / "stderr");
  EXPECT_NE(err.find("run: navd --config " + (dir / "hil" / "navd-hil.yaml").string()),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("warning: --speed 100"), std::string::npos) << err;
  EXPECT_EQ(nav::daemon::load_config_file((dir / "hil" / "navd-hil.yaml").string()).lcm.url,
            "memq://");
  EXPECT_FALSE(fs::exists(dir / "hil" / "heading"));  // the pty link goes with the player
}

::testing::Environment* const kCleanup =
    ::testing::AddGlobalTestEnvironment(new nav::sim::test::ScratchCleanup);

}  // namespace
