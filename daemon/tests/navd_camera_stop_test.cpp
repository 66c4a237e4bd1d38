// navd (live mode) stops on SIGTERM although its GigE camera vanished (killed -9) or hung
// (SIGSTOP): the real navd binary with a software-triggered camera on Aravis' fake
// GigE Vision camera, run by this test as a separate process (`arv-fake-gv-camera-0.8 -i
// 127.0.0.1`) in the test's own network namespace (support/net_namespace.h), so it cannot meet
// another test's fake on 127.0.0.1:3956. Once navd has written a frame the camera is killed or
// stopped, 1 s later navd gets SIGTERM.
// Contract asserted: exit status 0 within kStopBound of the SIGTERM (wall, including process
// teardown; generous for a loaded 2-core machine) and the shutdown checkpoint on disk. The
// measured stop time is in apps/navd/README.md (about 0.35 s; 14 s before the fix).
// Skips with the reason when the fake camera binary is absent or namespaces are not permitted.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "support/net_namespace.h"

extern char** environ;

namespace nav::daemon::service {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

constexpr const char* kFakeCamera = "arv-fake-gv-camera-0.8";
/// The contract: SIGTERM to exit, wall time (the contract is 1 s; this allows for load).
constexpr auto kStopBound = 2s;
// Before any thread: the fake camera and navd inherit the namespace.
const nav::tool::test::NetNamespace& kNet = nav::tool::test::isolated_network();

fs::path sim_yaml() { return fs::path(NAV_SOURCE_DIR) / "config/sim.yaml"; }

/// The fake camera's absolute path from PATH, or "".
std::string find_in_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path != nullptr ? path : "/usr/bin:/bin";
  for (std::size_t start = 0; start <= dirs.size();) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(start, end - start)) / name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    start = end + 1;
  }
  return "";
}

pid_t spawn(const std::vector<std::string>& argv, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  if (::posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

/// sim.yaml with its camera on the fake GigE camera (Mono8: the stock fake has no Mono12),
/// software-triggered at 4 Hz, frames written to `dir/images`, checkpoints in `dir/ckpt`.
fs::path write_config(const fs::path& dir) {
  std::ifstream in(sim_yaml());
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto replace = [&](const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) text.replace(at, from.size(), to);
  };
  replace("type: camera_gige\n    transport: {type: sim}",
          "type: camera_gige\n    transport: {type: gige, camera_id: \"127.0.0.1\"}");
  replace("pixel_format: mono12",
          "pixel_format: mono8\n      image_dir: " + (dir / "images").string());
  replace("frame_rate_hz: 0.33", "frame_rate_hz: 4");
  replace("path: /tmp/navd-sim/checkpoints", "path: " + (dir / "ckpt").string());
  const fs::path config = dir / "navd.yaml";
  std::ofstream(config) << text;
  return config;
}

bool wait_for_png(const fs::path& dir, Clock::duration limit) {
  const auto end = Clock::now() + limit;
  while (Clock::now() < end) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      if (e.path().extension() == ".png") return true;
    }
    std::this_thread::sleep_for(50ms);
  }
  return false;
}

std::size_t count_checkpoints(const fs::path& dir) {
  std::size_t n = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (e.path().extension() == ".ckpt") ++n;
  }
  return n;
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

struct StopResult {
  int status = -1;
  double stop_s = -1.0;
};

/// SIGTERM to navd; its wait status and the seconds to its exit (or -1 after 30 s: killed).
StopResult terminate(pid_t navd) {
  StopResult r;
  const auto start = Clock::now();
  ::kill(navd, SIGTERM);
  while (Clock::now() - start < 30s) {
    if (::waitpid(navd, &r.status, WNOHANG) == navd) {
      r.stop_s = std::chrono::duration<double>(Clock::now() - start).count();
      return r;
    }
    std::this_thread::sleep_for(5ms);
  }
  ::kill(navd, SIGKILL);
  ::waitpid(navd, &r.status, 0);
  return r;
}

class NavdCameraStop : public ::testing::TestWithParam<int> {};

TEST_P(NavdCameraStop, StopsWithinBoundAndWritesTheFinalCheckpoint) {
  if (!kNet.ok) GTEST_SKIP() << kNet.reason;
  const std::string fake = find_in_path(kFakeCamera);
  if (fake.empty()) GTEST_SKIP() << kFakeCamera << " not on PATH (Debian package aravis-tools)";
  const int camera_signal = GetParam();
  const fs::path dir =
      fs::temp_directory_path() /
      ("navd_camera_stop_" + std::to_string(::getpid()) + "_" + std::to_string(camera_signal));
  fs::remove_all(dir);
  fs::create_directories(dir / "images");
  const fs::path config = write_config(dir);
  const pid_t camera = spawn({fake, "-i", "127.0.0.1", "-s", "NAVSTOP"}, dir / "camera.log");
  ASSERT_GT(camera, 0) << "cannot start " << fake;
  std::this_thread::sleep_for(300ms);  // the fake listens on GVCP
  const pid_t navd =
      spawn({NAVD_PATH, "--config", config.string(), "--checkpoints", "--lcm-url", "memq://"},
            dir / "navd.log");
  ASSERT_GT(navd, 0);
  const bool streaming = wait_for_png(dir / "images", 20s);
  if (camera_signal != 0) ::kill(camera, camera_signal);
  std::this_thread::sleep_for(1s);  // navd's camera thread now waits on the silent device
  const StopResult stop = terminate(navd);
  ::kill(camera, SIGKILL);
  ::waitpid(camera, nullptr, 0);
  const std::string log = read_file(dir / "navd.log");
  ASSERT_TRUE(streaming) << "navd wrote no frame of the fake camera; navd log:\n" << log;
  std::printf("navd stopped in %.3f s (camera %s)\n", stop.stop_s,
              camera_signal == 0 ? "healthy" : strsignal(camera_signal));
  ASSERT_GE(stop.stop_s, 0.0) << "navd still running 30 s after SIGTERM; log:\n" << log;
  EXPECT_LT(stop.stop_s, std::chrono::duration<double>(kStopBound).count()) << log;
  ASSERT_TRUE(WIFEXITED(stop.status)) << "navd ended by signal; log:\n" << log;
  EXPECT_EQ(WEXITSTATUS(stop.status), 0) << log;
  EXPECT_GE(count_checkpoints(dir / "ckpt"), 1u) << "no shutdown checkpoint; log:\n" << log;
  if (camera_signal != 0) {
    EXPECT_NE(log.find("camera still in a device call"), std::string::npos) << log;
  }
  fs::remove_all(dir);
}

std::string signal_name(const ::testing::TestParamInfo<int>& info) {
  return info.param == 0 ? "Healthy" : info.param == SIGKILL ? "CameraKilled" : "CameraStopped";
}

INSTANTIATE_TEST_SUITE_P(Camera, NavdCameraStop, ::testing::Values(0, SIGKILL, SIGSTOP),
                         signal_name);

}  // namespace
}  // namespace nav::daemon::service
