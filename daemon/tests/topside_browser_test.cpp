// The topside page in a real browser while navd replays a short simulated dive: Debian's
// chromium driven by playwright-core (web/tests/browser.mjs) opens the page served by
// `navtool topside`, navd replays `navtool simulate --images 10` at 20x on the same LCM (the
// test's own network namespace), and the page must show the last nav_solution_t's depth within
// 0.01 m, as many delayed states and links as navd's last solution counts, a health row for
// every configured sensor, and every row stale within 3 s once the messages stop.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <navlcm/nav_solution_t.hpp>
#include <thread>

#include "nav/daemon/config/config.h"
#include "support/navtool_run.h"
#include "support/net_namespace.h"
#include "support/topside_process.h"

namespace nav::tool::test {
namespace {

namespace fs = std::filesystem;
const NetNamespace& kNet = isolated_network();

/// The last nav_solution_t heard on LCM (in a thread).
struct SolutionListener {
  lcm::LCM lcm{kIsolatedUdpmUrl};
  std::mutex mutex;
  navlcm::nav_solution_t last{};
  int count = 0;
  std::atomic<bool> running{true};
  std::thread thread;
  SolutionListener() {
    lcm.subscribe("NAVD_SOLUTION", &SolutionListener::on, this);
    thread = std::thread([this] {
      while (running) lcm.handleTimeout(50);
    });
  }
  ~SolutionListener() {
    running = false;
    thread.join();
  }
  void on(const lcm::ReceiveBuffer*, const std::string&, const navlcm::nav_solution_t* m) {
    std::lock_guard lock(mutex);
    last = *m;
    ++count;
  }
};

TEST(TopsideBrowser, PageShowsNavdReplayAndTurnsStale) {
  if (!kNet.ok) GTEST_SKIP() << kNet.reason;
  const fs::path dir = fs::temp_directory_path() / ("topside_browser_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path dive = dir / "dive";
  ASSERT_EQ(run_navtool("simulate --out '" + dive.string() + "' --images 10 --seed 4").exit_code, 0);
  const auto config = daemon::load_config_file((dive / "config.yaml").string());

  const pid_t topside = start_topside(kIsolatedUdpmUrl, 18082, dir,
                                     {"--config", (dive / "config.yaml").string()});
  ASSERT_GT(topside, 0) << file_text(dir / "topside.stderr");
  SolutionListener listener;
  const pid_t node = spawn_process({"node", NAV_TOPSIDE_WEB_DIR "/tests/browser.mjs",
                                    "http://127.0.0.1:18082/", dir.string()},
                                   dir / "node.stdout", dir / "node.stderr");
  for (int i = 0; i < 600 && !fs::exists(dir / "page-ready"); ++i) {
    if (wait_child(node, std::chrono::milliseconds(50)) != -1) break;
  }
  ASSERT_TRUE(fs::exists(dir / "page-ready")) << file_text(dir / "node.stderr");

  const pid_t navd = spawn_process(
      {NAVD_PATH, "--config", (dive / "config.yaml").string(), "--replay",
       (dive / "dive.lcmlog").string(), "--speed", "20", "--lcm-url", kIsolatedUdpmUrl, "--out",
       (dir / "navd").string()},
      dir / "navd.stdout", dir / "navd.stderr");
  const int navd_code = wait_child(navd, std::chrono::minutes(5));
  if (navd_code == -1) stop_child(navd);
  ASSERT_EQ(navd_code, 0) << file_text(dir / "navd.stderr");
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the last datagrams
  navlcm::nav_solution_t last;
  {
    std::lock_guard lock(listener.mutex);
    ASSERT_GT(listener.count, 0) << "no nav_solution_t heard from navd";
    last = listener.last;
  }
  std::ofstream(dir / "control.json")
      << nlohmann::json{{"num_delayed_states", last.num_delayed_states}}.dump();
  const int node_code = wait_child(node, std::chrono::seconds(60));
  if (node_code == -1) stop_child(node);
  stop_child(topside);
  ASSERT_EQ(node_code, 0) << file_text(dir / "node.stderr");

  const nlohmann::json shown = nlohmann::json::parse(file_text(dir / "result.json"));
  std::printf("page: %s\nnavd: depth %.4f m, %d states, %d links, %d solutions heard\n",
              shown.dump().c_str(), last.p_world_m[2], last.num_delayed_states,
              last.num_camera_links, listener.count);
  EXPECT_TRUE(shown["errors"].empty()) << shown["errors"];
  EXPECT_NEAR(std::stod(shown["depth_text"].get<std::string>()), last.p_world_m[2], 0.01);
  EXPECT_EQ(shown["n_states_text"], std::to_string(last.num_delayed_states));
  EXPECT_EQ(shown["n_links_text"], std::to_string(last.num_camera_links));
  EXPECT_GT(last.num_delayed_states, 0);
  for (const auto& sensor : config.sensors) {
    const auto& rows = shown["sensor_rows"];
    EXPECT_NE(std::find(rows.begin(), rows.end(), sensor.name), rows.end())
        << "no health row for " << sensor.name;
  }
  for (const auto& s : shown["health"]["sensors"]) {  // live when navd stopped, stale after
    EXPECT_EQ(shown["row_classes"][s["name"].get<std::string>()], "ok") << s["name"];
  }
  ASSERT_FALSE(shown["stale_after_last_health_ms"].is_null()) << "rows never turned stale";
  EXPECT_LE(shown["stale_after_last_sensor_message_ms"].get<double>(), 3000.0);
  std::printf("screenshots: %s/topside.png, topside-stale.png\n", dir.c_str());
  std::error_code ignored;  // keep the screenshots and logs, not the dive
  fs::remove_all(dive, ignored);
  fs::remove_all(dir / "navd", ignored);
}

}  // namespace
}  // namespace nav::tool::test
