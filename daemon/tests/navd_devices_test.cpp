// navd with a device sensor (live mode): an altimeter on a pseudo-terminal beside sim sensors
// (which get none) gets a device thread; its bytes go out on RAW_ALTIMETER_DEV and its
// health in health_t.sensors (LCM udpm with ttl=0 in the test's own network namespace,
// support/net_namespace.h; skipped with the reason where namespaces are not permitted).
#include <gtest/gtest.h>
#include <pty.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/health_t.hpp>
#include <navlcm/raw_bytes_t.hpp>
#include <thread>

#include "support/net_namespace.h"
#include "support/udpm_probe.h"

namespace nav::daemon::service {
namespace {

namespace fs = std::filesystem;
constexpr const char* kUdpmUrl = nav::tool::test::kIsolatedUdpmUrl;
// navd and this test in a network namespace of their own (before any thread starts).
const nav::tool::test::NetNamespace& kNet = nav::tool::test::isolated_network();

fs::path sim_yaml() {
  const fs::path rel = "config/sim.yaml";
  const auto beside = fs::path(__FILE__).parent_path().parent_path().parent_path();
  return fs::exists(beside / rel) ? beside / rel : rel;
}

struct Received {
  int raw = 0;
  navlcm::health_t health{};
  bool have_sensor_health = false;
  void on_raw(const lcm::ReceiveBuffer*, const std::string&, const navlcm::raw_bytes_t* m) {
    if (m->device == "altimeter_dev") ++raw;
  }
  void on_health(const lcm::ReceiveBuffer*, const std::string&, const navlcm::health_t* m) {
    if (m->num_sensors > 0) {
      health = *m;
      have_sensor_health = true;
    }
  }
};

TEST(NavdDevices, SerialSensorThreadPublishesRawBytesAndHealth) {
  if (!kNet.ok) GTEST_SKIP() << kNet.reason;
  lcm::LCM lcm(kUdpmUrl);
  if (!lcm.good()) GTEST_SKIP() << "LCM cannot open " << kUdpmUrl << " here (no multicast)";
  if (!nav::tool::test::udpm_loops_back(lcm, "NAVD_DEVICES_TEST_PROBE")) {
    GTEST_SKIP() << "udpm ttl=0 does not loop back in the test's namespace";
  }
  int master = -1, slave = -1;
  char name[256] = {};
  ASSERT_EQ(::openpty(&master, &slave, name, nullptr, nullptr), 0);
  ::close(slave);
  const fs::path config =
      fs::temp_directory_path() / ("navd_devices_" + std::to_string(::getpid()) + ".yaml");
  {
    std::ifstream in(sim_yaml());
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string sensor =
        "sensors:\n  - name: altimeter_dev\n    type: altimeter\n"
        "    transport: {type: serial, device: " +
        std::string(name) + ", baud: 9600}\n    latency_ms: 30\n";
    text.replace(text.find("sensors:\n"), 9, sensor);
    std::ofstream(config) << text;
  }
  Received got;
  lcm.subscribe("RAW_ALTIMETER_DEV", &Received::on_raw, &got);
  lcm.subscribe("NAVD_HEALTH", &Received::on_health, &got);
  std::atomic<bool> done{false};
  std::thread sensor([&] {
    const std::string line = "  3.42m\r\n";
    while (!done.load()) {
      (void)!::write(master, line.data(), line.size());
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  std::atomic<int> code{-1};
  std::thread navd([&] {
    const std::string cmd = std::string("'") + NAVD_PATH + "' --config '" + config.string() +
                            "' --duration-s 2.5 --lcm-url '" + kUdpmUrl +
                            "' >/dev/null 2>&1";
    const int status = std::system(cmd.c_str());
    code.store(WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    done.store(true);
  });
  while (!done.load()) lcm.handleTimeout(20);
  for (int i = 0; i < 10; ++i) lcm.handleTimeout(20);
  navd.join();
  sensor.join();
  ::close(master);
  fs::remove(config);
  ASSERT_EQ(code.load(), 0);
  EXPECT_GT(got.raw, 5);
  ASSERT_TRUE(got.have_sensor_health);
  ASSERT_EQ(got.health.sensors.size(), 1u);  // the sim sensors have no device thread
  EXPECT_EQ(got.health.sensors[0].name, "altimeter_dev");
  EXPECT_GT(got.health.sensors[0].records, 5);
  EXPECT_EQ(got.health.sensors[0].decode_errors, 0);
}

}  // namespace
}  // namespace nav::daemon::service
