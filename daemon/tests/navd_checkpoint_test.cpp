// navd checkpoints end to end: a simulated dive (navtool simulate) replayed
// by the real navd with --checkpoints at 100x real time is killed with SIGKILL at random points
// and restarted each time; the last start finishes the dive. Its replay output (delayed states
// with bounds, links, trajectory) must equal an uninterrupted run's, with every delayed state,
// and the restarts must have resumed from checkpoints. Before the last start the newest
// checkpoint is truncated: navd reports it with the reason and resumes from the previous one.
// SIGTERM writes the shutdown checkpoint (no periodic one falls in the run), which the next
// start resumes.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>

#include "nav/daemon/checkpoint/checkpoint.h"
#include "support/navtool_run.h"

namespace nav::tool::test {
namespace {

namespace fs = std::filesystem;

/// Starts `command` with /bin/sh (which execs navd, so the pid is navd's).
pid_t start_shell(const std::string& command) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

int wait_status(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

/// Polls `file` until it contains `text` or `timeout` passes (then the caller's checks fail).
void wait_for_text(const fs::path& file, const std::string& text, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (fs::exists(file) && read_text(file).find(text) != std::string::npos) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

/// Waits until process `pid` blocks SIGTERM (navd's main does that first: from then on a SIGTERM
/// is a clean stop, before it the default action kills it), at most `timeout`.
bool wait_sigterm_blocked(pid_t pid, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    std::ifstream status("/proc/" + std::to_string(pid) + "/status");
    for (std::string line; std::getline(status, line);) {
      if (line.rfind("SigBlk:", 0) == 0 &&
          (std::stoull(line.substr(7), nullptr, 16) >> (SIGTERM - 1)) & 1u) {
        return true;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

TEST(NavdCheckpoints, KilledReplayResumesToTheUninterruptedMap) {
  const fs::path root = fs::temp_directory_path() / ("navd_ckpt_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  const std::string dive = (root / "dive").string();
  ASSERT_EQ(run_navtool("simulate --out '" + dive + "' --images 20 --seed 5").exit_code, 0);
  // The dive's config with the checkpoints in this test's directory, every 0.1 s of wall time.
  std::string config = read_text(dive + "/config.yaml");
  const std::string old_path = "path: /tmp/navd-sim/checkpoints";
  const auto at = config.find(old_path);
  ASSERT_NE(at, std::string::npos) << "simulated config.yaml changed";
  config.replace(at, old_path.size(), "path: " + (root / "checkpoints").string());
  const auto period = config.find("period_s: 30");
  ASSERT_NE(period, std::string::npos);
  config.replace(period, 12, "period_s: 0.1");
  // Byte-identical files need the block-Jacobi recovery: a restored kept factor (sim.yaml's)
  // starts from a fresh factorisation (docs/formats.md "Checkpoints").
  const std::string kept = "recovery_preconditioner: kept_factor";
  const auto recovery = config.find(kept);
  ASSERT_NE(recovery, std::string::npos) << "simulated config.yaml changed";
  config.replace(recovery, kept.size(), "recovery_preconditioner: block_jacobi");
  // The lag is a setting of the kept factor only; whatever sim.yaml's value, it becomes 0.
  const std::string lag = "recovery_renewal_lag:";
  const auto lag_at = config.find(lag);
  ASSERT_NE(lag_at, std::string::npos) << "simulated config.yaml changed";
  config.replace(lag_at, config.find('\n', lag_at) - lag_at, lag + " 0");
  std::ofstream(root / "config.yaml") << config;

  auto navd = [&](const std::string& extra, const std::string& out, const std::string& log) {
    return "exec '" + std::string(NAVD_PATH) + "' --config '" + (root / "config.yaml").string() +
           "' --lcm-url memq:// --replay '" + dive + "/dive.lcmlog' " + extra + " --out '" +
           (root / out).string() + "' > /dev/null 2>> '" + (root / log).string() + "'";
  };
  ASSERT_EQ(wait_status(start_shell(navd("--as-fast-as-possible", "reference", "ref.err"))), 0)
      << read_text(root / "ref.err");

  std::mt19937 rng(3);
  std::uniform_real_distribution<double> when_s(0.4, 2.4);  // the paced run takes ~2.8 s
  int kills = 0;
  for (int i = 0; i < 4; ++i) {
    const pid_t pid = start_shell(navd("--speed 100 --checkpoints", "killed", "runs.err"));
    std::this_thread::sleep_for(std::chrono::duration<double>(when_s(rng)));
    ::kill(pid, SIGKILL);
    const int code = wait_status(pid);
    if (code == -SIGKILL) ++kills;
    ASSERT_TRUE(code == 0 || code == -SIGKILL) << code << read_text(root / "runs.err");
  }
  EXPECT_GE(kills, 3);
  const std::vector<std::uint64_t> seqs = nav::daemon::list_checkpoints(root / "checkpoints");
  ASSERT_GE(seqs.size(), 2u) << read_text(root / "runs.err");
  const fs::path newest = nav::daemon::checkpoint_path(root / "checkpoints", seqs.back());
  fs::resize_file(newest, fs::file_size(newest) - 100);
  ASSERT_EQ(
      wait_status(start_shell(navd("--as-fast-as-possible --checkpoints", "final", "final.err"))),
      0)
      << read_text(root / "final.err");
  const std::string runs = read_text(root / "runs.err"), last = read_text(root / "final.err");
  std::printf("%d kills; resumes: %s", kills, runs.c_str());
  EXPECT_NE(runs.find("resumed from"), std::string::npos) << runs;
  EXPECT_NE(last.find(newest.filename().string() + " skipped: truncated"), std::string::npos)
      << last;
  EXPECT_NE(last.find("resumed from"), std::string::npos) << last;
  for (const char* file : {"states.csv", "links.csv", "trajectory.csv", "proposals.csv",
                           "dead_reckoning.csv", "information_blocks.csv"}) {
    const std::string expected = read_text(root / "reference" / file);
    EXPECT_FALSE(expected.empty()) << file;
    EXPECT_EQ(read_text(root / "final" / file), expected) << file << " differs";
  }
  // Every delayed state is there: one states.csv row per image (plus the header).
  EXPECT_EQ(lines_of(read_text(root / "final" / "states.csv")).size(), 21u);
  std::error_code ignored;
  fs::remove_all(root, ignored);
}

TEST(NavdCheckpoints, SigtermWritesTheShutdownCheckpoint) {
  const fs::path root =
      fs::temp_directory_path() / ("navd_ckpt_term_" + std::to_string(::getpid()));
  fs::remove_all(root);
  fs::create_directories(root);
  const std::string dive = (root / "dive").string();
  ASSERT_EQ(run_navtool("simulate --out '" + dive + "' --images 10 --seed 6").exit_code, 0);
  // No periodic checkpoint within the run (period 1000 s): only the shutdown one.
  std::string config = read_text(dive + "/config.yaml");
  const std::string old_path = "path: /tmp/navd-sim/checkpoints";
  const auto at = config.find(old_path);
  ASSERT_NE(at, std::string::npos);
  config.replace(at, old_path.size(), "path: " + (root / "checkpoints").string());
  const auto period = config.find("period_s: 30");
  ASSERT_NE(period, std::string::npos);
  config.replace(period, 12, "period_s: 1000");
  std::ofstream(root / "config.yaml") << config;
  const std::string command = "exec '" + std::string(NAVD_PATH) + "' --config '" +
                              (root / "config.yaml").string() + "' --lcm-url memq:// --replay '" +
                              dive + "/dive.lcmlog' --speed 50 --checkpoints > /dev/null 2>> '" +
                              (root / "err.txt").string() + "'";
  const pid_t pid = start_shell(command);
  // Under load navd may take longer than the sleep to reach main (exec, dynamic linking).
  if (!wait_sigterm_blocked(pid, std::chrono::seconds(20))) {
    ::kill(pid, SIGKILL);
    (void)wait_status(pid);
    FAIL() << "navd did not block SIGTERM within 20 s: " << read_text(root / "err.txt");
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  ::kill(pid, SIGTERM);
  EXPECT_EQ(wait_status(pid), 0) << read_text(root / "err.txt");
  EXPECT_EQ(nav::daemon::list_checkpoints(root / "checkpoints").size(), 1u);
  const pid_t again = start_shell(command);
  wait_for_text(root / "err.txt", "resumed from", std::chrono::seconds(20));
  ::kill(again, SIGTERM);
  EXPECT_EQ(wait_status(again), 0) << read_text(root / "err.txt");
  const std::string err = read_text(root / "err.txt");
  EXPECT_NE(err.find("resumed from"), std::string::npos) << err;
  std::error_code ignored;
  fs::remove_all(root, ignored);
}

}  // namespace
}  // namespace nav::tool::test
