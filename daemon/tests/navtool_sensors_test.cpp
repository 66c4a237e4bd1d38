// `navtool sensors`: the device threads in a binary — an NMEA heading sensor on a
// pseudo-terminal is read, published on LCM and decoded; per-sensor health as JSON.
#include <gtest/gtest.h>
#include <pty.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "nav/drivers/codecs/nmea.h"
#include "support/navtool_run.h"

namespace nav::tool::test {
namespace {

namespace fs = std::filesystem;

TEST(NavtoolSensors, ReadsASerialSensorAndReportsItsHealth) {
  int master = -1, slave = -1;
  char name[256] = {};
  ASSERT_EQ(::openpty(&master, &slave, name, nullptr, nullptr), 0);
  ::close(slave);
  const fs::path config =
      fs::temp_directory_path() / ("navtool_sensors_" + std::to_string(::getpid()) + ".yaml");
  {
    std::ofstream out(config);
    out << "sensors:\n"
           "  - name: heading\n"
           "    type: heading_nmea\n"
           "    transport: {type: serial, device: "
        << name
        << ", baud: 115200}\n"
           "    latency_ms: 20\n"
           "  - {name: depth, type: pressure_paro, transport: {type: sim}}\n"
           "lcm: {url: 'memq://'}\n";
  }
  std::atomic<bool> done{false};
  std::thread sensor([&] {
    drivers::NmeaHeading h;
    h.heading_rad = 1.0;
    const std::string line = drivers::encode_nmea(h);
    while (!done.load()) {
      (void)!::write(master, line.data(), line.size());
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  const NavtoolOutput r =
      run_navtool("sensors --config '" + config.string() + "' --duration-s 1.5");
  done.store(true);
  sensor.join();
  ::close(master);
  fs::remove(config);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["device_threads"], 1);  // the sim depth sensor has no device
  ASSERT_EQ(j["sensors"].size(), 1u);
  const auto& s = j["sensors"][0];
  EXPECT_EQ(s["name"], "heading");
  EXPECT_GT(s["records"].get<int>(), 20);
  EXPECT_EQ(s["measurements"], s["records"]);
  EXPECT_EQ(j["measurements"], s["measurements"]);
  EXPECT_EQ(s["decode_errors"], 0);
  EXPECT_EQ(s["queue_drops"], 0);
  EXPECT_GT(j["raw_published"].get<int>(), 0);
}

TEST(NavtoolSensors, BadConfigIsAnErrorNamingTheFile) {
  const NavtoolOutput r = run_navtool("sensors --config /nonexistent/navd.yaml --duration-s 0.1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("/nonexistent/navd.yaml"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace nav::tool::test
