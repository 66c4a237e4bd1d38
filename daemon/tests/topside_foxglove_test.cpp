// navtool topside's Foxglove endpoint against the npm @foxglove/ws-protocol client: the test
// publishes a known nav_solution_t and bounds_snapshot_t on LCM udpm (in its own network
// namespace) while web/tests/foxglove_client.mjs subscribes to /navd/pose and /navd/bounds and
// checks the decoded PoseInFrame and SceneUpdate against the same values.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/bounds_snapshot_t.hpp>
#include <navlcm/nav_solution_t.hpp>

#include "support/net_namespace.h"
#include "support/topside_process.h"

namespace nav::tool::test {
namespace {

namespace fs = std::filesystem;
const NetNamespace& kNet = isolated_network();

TEST(TopsideFoxglove, WsProtocolClientDecodesPoseAndBoundsAsPublished) {
  if (!kNet.ok) GTEST_SKIP() << kNet.reason;
  const fs::path dir = fs::temp_directory_path() / ("topside_fox_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const pid_t topside = start_topside(kIsolatedUdpmUrl, 18081, dir);
  ASSERT_GT(topside, 0) << file_text(dir / "topside.stderr");

  navlcm::nav_solution_t sol{};
  sol.utime = 1'700'000'000'000'000;
  const double p[3] = {12.5, -3.25, 41.0}, rph[3] = {0.02, -0.05, 1.9};
  for (int i = 0; i < 3; ++i) sol.p_world_m[i] = p[i], sol.rph_rad[i] = rph[i];
  navlcm::bounds_snapshot_t snap{};
  snap.utime = sol.utime;
  nlohmann::json states = nlohmann::json::array();
  for (int k = 0; k < 2; ++k) {
    navlcm::delayed_state_bound_t b{};
    b.utime = sol.utime;
    b.state_id = 10 + k;
    const double mean[3] = {1.0 + k, 2.0 * k, 30.0}, var[3] = {0.04 * (k + 1), 0.09, 0.01};
    for (int i = 0; i < 3; ++i) b.mean_pose[i] = mean[i], b.bound_covariance[7 * i] = var[i];
    snap.states.push_back(b);
    states.push_back({{"state_id", b.state_id},
                      {"mean_m", {mean[0], mean[1], mean[2]}},
                      {"variances_m2", {var[0], var[1], var[2]}}});
  }
  snap.num_states = 2;
  std::ofstream(dir / "expected.json")
      << nlohmann::json{{"p_world_m", p}, {"rph_rad", rph}, {"states", states}}.dump();

  const pid_t node = spawn_process(
      {"node", "--experimental-websocket", NAV_TOPSIDE_WEB_DIR "/tests/foxglove_client.mjs",
       "ws://127.0.0.1:18081/", (dir / "expected.json").string()},
      dir / "node.stdout", dir / "node.stderr");
  lcm::LCM lcm(kIsolatedUdpmUrl);
  ASSERT_TRUE(lcm.good());
  int code = -1;
  for (int i = 0; i < 250 && code == -1; ++i) {  // 25 s at 10 Hz until the client is satisfied
    lcm.publish("NAVD_SOLUTION", &sol);
    lcm.publish("NAVD_BOUNDS_SNAPSHOT", &snap);
    code = wait_child(node, std::chrono::milliseconds(100));
  }
  if (code == -1) stop_child(node);
  stop_child(topside);
  EXPECT_EQ(code, 0) << file_text(dir / "node.stdout") << file_text(dir / "node.stderr");
  std::error_code ignored;
  if (code == 0) fs::remove_all(dir, ignored);
}

}  // namespace
}  // namespace nav::tool::test
