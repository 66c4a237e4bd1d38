// End-to-end tests of `navtool survey` (NAVTOOL_PATH; apps/navtool/cmd_survey.cpp):
// config/sim.yaml with its `sim` dive in a private directory and few images. The first run
// simulates the dive and replays it through navd's replay mode as fast as possible with --out
// (replay outputs, then the report, whose directory the last stderr line names); the second
// reuses the dive and gives the same outputs. Also: the systemd notifications (READY, WATCHDOG,
// STATUS, STOPPING) on a test-owned NOTIFY_SOCKET, a clean SIGTERM shutdown within 1 s with exit
// status 0, and nav_solution_t / health_t over LCM udpm with ttl=0 in the test's own network
// namespace (support/net_namespace.h; skipped with the reason where namespaces are not
// permitted): the published pose covariance is symmetric positive semi-definite, health_t
// carries CPU, RSS and each sensor's innovation record.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/health_t.hpp>
#include <navlcm/nav_solution_t.hpp>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/net_namespace.h"
#include "support/udpm_probe.h"

namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr const char* kUdpmUrl = nav::tool::test::kIsolatedUdpmUrl;
// navtool and this test in a network namespace of their own (before any thread starts).
const nav::tool::test::NetNamespace& kNet = nav::tool::test::isolated_network();

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A `navtool survey` child process with stdout/stderr redirected to files in a private
/// directory.
class SurveyProcess {
 public:
  using Env = std::vector<std::pair<std::string, std::string>>;
  /// `no_network`: navtool runs in a network namespace of its own without any route.
  explicit SurveyProcess(const std::vector<std::string>& args, const Env& env = {},
                         bool no_network = false) {
    dir_ = std::filesystem::temp_directory_path() /
           ("navtool_survey_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter_++));
    std::filesystem::create_directories(dir_);
    pid_ = ::fork();
    if (pid_ == 0) {
      for (const auto& [name, value] : env) ::setenv(name.c_str(), value.c_str(), 1);
      if (no_network && !nav::tool::test::enter_network_without_multicast().ok) ::_exit(125);
      exec_child(args);
    }
  }
  ~SurveyProcess() {
    if (pid_ > 0 && !reaped_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    std::filesystem::remove_all(dir_);
  }
  pid_t pid() const { return pid_; }
  /// Waits up to `timeout`; returns the exit code, -1 if still running or killed by a signal.
  int wait_exit(std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        reaped_ = true;
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return -1;
  }
  std::string out() const { return slurp(dir_ / "stdout"); }
  std::string err() const { return slurp(dir_ / "stderr"); }

 private:
  [[noreturn]] void exec_child(const std::vector<std::string>& args) {
    std::vector<char*> argv;
    std::string path = NAVTOOL_PATH, command = "survey";
    argv.push_back(path.data());
    argv.push_back(command.data());
    std::vector<std::string> copy = args;
    for (std::string& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    if (!std::freopen((dir_ / "stdout").c_str(), "w", stdout) ||
        !std::freopen((dir_ / "stderr").c_str(), "w", stderr)) {
      ::_exit(126);
    }
    ::execv(path.c_str(), argv.data());
    ::_exit(127);
  }
  static inline int counter_ = 0;
  std::filesystem::path dir_;
  pid_t pid_ = -1;
  bool reaped_ = false;
};

/// A private directory with config/sim.yaml whose `sim` dive is `dir/dive` with `images`.
class SimDir {
 public:
  explicit SimDir(int images) {
    dir_ = std::filesystem::temp_directory_path() /
           ("navtool_survey_test_dir_" + std::to_string(::getpid()) + "_" +
            std::to_string(counter_++));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    std::string yaml = slurp("config/sim.yaml");
    const std::size_t at = yaml.find("\nsim:");
    EXPECT_NE(at, std::string::npos) << "config/sim.yaml has no `sim` section";
    yaml = yaml.substr(0, at + 1) + "sim:\n  dive_dir: " + dive().string() +
           "\n  seed: 1\n  images: " + std::to_string(images) + "\n";
    std::ofstream(config()) << yaml;
  }
  ~SimDir() { std::filesystem::remove_all(dir_); }
  std::filesystem::path config() const { return dir_ / "sim.yaml"; }
  std::filesystem::path dive() const { return dir_ / "dive"; }
  std::filesystem::path out(const std::string& name) const { return dir_ / name; }
  std::filesystem::path checkpoints() const { return dir_ / "checkpoints"; }
  /// Checkpoints in checkpoints() every `period_s` of wall time.
  void set_checkpoints(double period_s) const {
    std::string yaml = slurp(config());
    const std::string path = "path: /tmp/navd-sim/checkpoints", period = "period_s: 30";
    ASSERT_NE(yaml.find(path), std::string::npos) << "config/sim.yaml checkpoint.path changed";
    yaml.replace(yaml.find(path), path.size(), "path: " + checkpoints().string());
    ASSERT_NE(yaml.find(period), std::string::npos) << "config/sim.yaml checkpoint.period_s";
    yaml.replace(yaml.find(period), period.size(), "period_s: " + std::to_string(period_s));
    std::ofstream(config()) << yaml;
  }

 private:
  static inline int counter_ = 0;
  std::filesystem::path dir_;
};

TEST(NavtoolSurvey, SimulatesReplaysReportsThenReusesTheDive) {
  constexpr int kImages = 12;
  const SimDir sim(kImages);
  SurveyProcess first({"--config", sim.config().string(), "--as-fast-as-possible", "--out",
                       sim.out("out1").string()});
  ASSERT_EQ(first.wait_exit(std::chrono::seconds(60)), 0) << first.err();
  EXPECT_NE(first.err().find("simulating the dive"), std::string::npos) << first.err();
  EXPECT_NE(first.err().find("100 %"), std::string::npos) << first.err();  // progress
  EXPECT_TRUE(std::filesystem::exists(sim.dive() / "dive.lcmlog"));
  EXPECT_TRUE(std::filesystem::exists(sim.dive() / "sim.json"));
  const json j = json::parse(first.out());
  EXPECT_EQ(j["error"].get<std::string>(), "");
  EXPECT_EQ(j["images"].get<int>(), kImages);
  EXPECT_EQ(j["delayed_states"].get<int>(), kImages);
  EXPECT_GE(j["links_accepted"].get<int>(), kImages - 1);  // at least the temporal chain
  EXPECT_EQ(j["update_failures"].get<int>(), 0);
  EXPECT_EQ(j["decode_errors"].get<int>(), 0);
  EXPECT_DOUBLE_EQ(j["conservative_fraction"].get<double>(), 1.0);
  for (const char* f : {"summary.json", "states.csv", "trajectory.csv", "links.csv", "metrics.json",
                        "fig1_trajectory.png"}) {
    EXPECT_TRUE(std::filesystem::exists(sim.out("out1") / f)) << f;
  }
  const json metrics = json::parse(slurp(sim.out("out1") / "metrics.json"));
  EXPECT_EQ(metrics["delayed_states"].get<int>(), kImages);
  // The output ends by naming the report's directory and files.
  std::string err = first.err();
  while (!err.empty() && err.back() == '\n') err.pop_back();
  const std::string last_line = err.substr(err.rfind('\n') + 1);
  EXPECT_NE(last_line.find("report"), std::string::npos) << last_line;
  EXPECT_NE(last_line.find(sim.out("out1").string() + ": metrics.json, fig1_trajectory.png"),
            std::string::npos)
      << last_line;

  SurveyProcess second({"--config", sim.config().string(), "--as-fast-as-possible", "--out",
                        sim.out("out2").string()});
  ASSERT_EQ(second.wait_exit(std::chrono::seconds(60)), 0) << second.err();
  EXPECT_NE(second.err().find("reusing the simulated dive"), std::string::npos) << second.err();
  EXPECT_EQ(second.err().find("simulating"), std::string::npos) << second.err();
  for (const char* f : {"states.csv", "trajectory.csv", "links.csv"}) {  // deterministic replay
    EXPECT_EQ(slurp(sim.out("out1") / f), slurp(sim.out("out2") / f)) << f;
  }
}

TEST(NavtoolSurvey, ImagesOptionOtherThanTheCachedDiveSimulatesAgain) {
  const SimDir sim(6);
  SurveyProcess first({"--config", sim.config().string(), "--as-fast-as-possible"});
  ASSERT_EQ(first.wait_exit(std::chrono::seconds(60)), 0) << first.err();
  SurveyProcess second(
      {"--config", sim.config().string(), "--images", "8", "--as-fast-as-possible"});
  ASSERT_EQ(second.wait_exit(std::chrono::seconds(60)), 0) << second.err();
  EXPECT_NE(second.err().find("not the config's"), std::string::npos) << second.err();
  EXPECT_EQ(json::parse(second.out())["images"].get<int>(), 8);
}

TEST(NavtoolSurvey, VisionRendersTheFramesRegistersThemAndADiveWithFramesIsReused) {
  constexpr int kImages = 6;
  const SimDir sim(kImages);
  SurveyProcess plain({"--config", sim.config().string(), "--as-fast-as-possible"});
  ASSERT_EQ(plain.wait_exit(std::chrono::seconds(60)), 0) << plain.err();
  EXPECT_FALSE(std::filesystem::exists(sim.dive() / "images"));
  SurveyProcess visual({"--config", sim.config().string(), "--vision", "--as-fast-as-possible"});
  ASSERT_EQ(visual.wait_exit(std::chrono::seconds(300)), 0) << visual.err();
  EXPECT_NE(visual.err().find("simulated without frames"), std::string::npos) << visual.err();
  int frames = 0;
  for (const auto& e : std::filesystem::directory_iterator(sim.dive() / "images")) {
    frames += e.path().extension() == ".png" ? 1 : 0;
  }
  EXPECT_GE(frames, kImages);
  const json j = json::parse(visual.out());
  EXPECT_EQ(j["error"].get<std::string>(), "");
  ASSERT_TRUE(j["vision"].is_object()) << visual.out();  // navd's own stage answered
  EXPECT_GT(j["vision"]["answered"].get<int>(), 0);
  EXPECT_GT(j["vision"]["succeeded"].get<int>(), 0) << j["vision"]["last_failure"];
  EXPECT_GT(j["links_accepted"].get<int>(), 0);
  // The rendered dive serves a run without vision too: no new simulation.
  SurveyProcess again({"--config", sim.config().string(), "--as-fast-as-possible"});
  ASSERT_EQ(again.wait_exit(std::chrono::seconds(60)), 0) << again.err();
  EXPECT_NE(again.err().find("reusing the simulated dive"), std::string::npos) << again.err();
}

TEST(NavtoolSurvey, ConfigWithoutSimSectionIsAConfigurationError) {
  const SimDir sim(6);
  std::string yaml = slurp(sim.config());
  yaml = yaml.substr(0, yaml.find("\nsim:") + 1);
  std::ofstream(sim.out("nosim.yaml")) << yaml;
  SurveyProcess survey({"--config", sim.out("nosim.yaml").string()});
  EXPECT_EQ(survey.wait_exit(std::chrono::seconds(20)), 2);
  EXPECT_NE(survey.err().find("nosim.yaml: sim: no `sim` section"), std::string::npos)
      << survey.err();
  EXPECT_TRUE(survey.out().empty()) << survey.out();
}

/// A datagram socket bound to a fresh path, as systemd's NOTIFY_SOCKET.
class NotifySocket {
 public:
  NotifySocket() {
    path_ = (std::filesystem::temp_directory_path() /
             ("navtool_survey_test_notify_" + std::to_string(::getpid())))
                .string();
    std::filesystem::remove(path_);
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", path_.c_str());
    bound_ = fd_ >= 0 && ::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0;
    timeval tv{0, 20'000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~NotifySocket() {
    if (fd_ >= 0) ::close(fd_);
    std::filesystem::remove(path_);
  }
  bool bound() const { return bound_; }
  const std::string& path() const { return path_; }
  /// One datagram, or "" after the 20 ms receive timeout.
  std::string receive() {
    char buffer[4096];
    const ssize_t n = ::recv(fd_, buffer, sizeof buffer, 0);
    return n > 0 ? std::string(buffer, static_cast<size_t>(n)) : std::string();
  }

 private:
  std::string path_;
  int fd_ = -1;
  bool bound_ = false;
};

TEST(NavtoolSurvey, NotifiesSystemdReadyWatchdogStatusStopping) {
  NotifySocket socket;
  ASSERT_TRUE(socket.bound()) << "cannot bind " << socket.path();
  const SimDir sim(12);  // ~100 s of dive: ~1 s at 100x
  SurveyProcess survey({"--config", sim.config().string(), "--speed", "100"},
                       {{"NOTIFY_SOCKET", socket.path()}, {"WATCHDOG_USEC", "200000"}});
  std::vector<std::string> messages;
  int code = -1;
  const auto deadline = Clock::now() + std::chrono::seconds(20);
  while (Clock::now() < deadline && code == -1) {
    for (std::string m = socket.receive(); !m.empty(); m = socket.receive()) messages.push_back(m);
    code = survey.wait_exit(std::chrono::milliseconds(1));
  }
  for (std::string m = socket.receive(); !m.empty(); m = socket.receive()) messages.push_back(m);
  ASSERT_EQ(code, 0) << survey.err();
  auto count = [&](const std::string& prefix) {
    int n = 0;
    for (const std::string& m : messages) n += m.rfind(prefix, 0) == 0 ? 1 : 0;
    return n;
  };
  ASSERT_FALSE(messages.empty());
  EXPECT_EQ(messages.front().rfind("STATUS=simulating ", 0), 0u) << messages.front();
  EXPECT_EQ(count("READY=1\nSTATUS=replaying "), 1);
  EXPECT_GE(count("WATCHDOG=1"), 5);  // ~1 s replay, watchdog period 100 ms
  EXPECT_EQ(messages.back(), "STOPPING=1");
}

TEST(NavtoolSurvey, SigtermStopsWithinOneSecondAndExitsZero) {
  const SimDir sim(12);  // ~100 s of dive at 5x: still replaying when SIGTERM comes
  SurveyProcess survey({"--config", sim.config().string(), "--speed", "5"});
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  ASSERT_EQ(survey.wait_exit(std::chrono::milliseconds(1)), -1)
      << "navtool survey ended early: " << survey.err();
  const auto sent = Clock::now();
  ASSERT_EQ(::kill(survey.pid(), SIGTERM), 0);
  const int code = survey.wait_exit(std::chrono::seconds(5));
  const double stop_s = std::chrono::duration<double>(Clock::now() - sent).count();
  EXPECT_EQ(code, 0) << survey.err();
  EXPECT_LT(stop_s, 1.0);
  const json j = json::parse(survey.out());
  EXPECT_GT(j["measurements"].get<int>(), 0);
  EXPECT_LT(j["images"].get<int>(), 12);  // stopped before the end
}

/// The last health_t of a replay: memory from /proc, and an innovation record for each sensor
/// of config/sim.yaml that the filter updates from.
void expect_health_usage_and_innovations(const navlcm::health_t& h) {
  std::printf("last health_t: cpu %.1f %%, rss %.1f MiB, peak %.1f MiB\n", h.cpu_percent, h.rss_mb,
              h.peak_rss_mb);
  for (const navlcm::sensor_health_t& s : h.sensors) {
    std::printf("  %-10s updates %lld rejected %lld NIS mean %.3f (expected %.2f) last %.3f\n",
                s.name.c_str(), static_cast<long long>(s.updates),
                static_cast<long long>(s.rejected_updates), s.nis_mean, s.nis_expected, s.nis_last);
  }
  EXPECT_GT(h.rss_mb, 10.0);  // the replay with the map: tens of MB
  EXPECT_GE(h.peak_rss_mb, h.rss_mb);
  EXPECT_GE(h.cpu_percent, 0.0);
  for (const char* name : {"dvl", "heading", "depth"}) {
    const auto it = std::find_if(h.sensors.begin(), h.sensors.end(),
                                 [&](const navlcm::sensor_health_t& s) { return s.name == name; });
    ASSERT_NE(it, h.sensors.end()) << "no health entry for sensor " << name;
    EXPECT_GT(it->updates, 0) << name;
    EXPECT_EQ(it->rejected_updates, 0) << name;
    EXPECT_GT(it->nis_last, 0.0) << name;
    // Over the last period (-1 and 0 when the replay ended right after the previous message).
    if (it->nis_mean >= 0.0) {
      EXPECT_GE(it->nis_expected, 1.0) << name;
    }
    ASSERT_GT(it->num_components, 0) << name;
    ASSERT_EQ(it->num_components, static_cast<int>(it->last.size())) << name;
    EXPECT_TRUE(it->last[0].fused) << name;
    EXPECT_GT(it->last[0].innovation_variance, it->last[0].observation_variance) << name;
  }
}

TEST(NavtoolSurvey, PublishesSolutionAndHealthOverUdpm) {
  if (!kNet.ok) GTEST_SKIP() << kNet.reason;
  lcm::LCM lcm(kUdpmUrl);
  ASSERT_TRUE(lcm.good()) << "LCM cannot open " << kUdpmUrl << " in the test's namespace";
  ASSERT_TRUE(nav::tool::test::udpm_loops_back(lcm, "NAVTOOL_SURVEY_TEST_PROBE"));
  int solutions = 0, health = 0;
  navlcm::nav_solution_t last{};
  navlcm::health_t last_health{};
  double max_cpu_percent = 0.0;
  struct Handler {
    int* solutions;
    int* health;
    navlcm::nav_solution_t* last;
    navlcm::health_t* last_health;
    double* max_cpu_percent;
    void on_solution(const lcm::ReceiveBuffer*, const std::string&,
                     const navlcm::nav_solution_t* m) {
      ++*solutions;
      *last = *m;
    }
    void on_health(const lcm::ReceiveBuffer*, const std::string&, const navlcm::health_t* m) {
      ++*health;
      *last_health = *m;
      *max_cpu_percent = std::max(*max_cpu_percent, m->cpu_percent);
    }
  } handler{&solutions, &health, &last, &last_health, &max_cpu_percent};
  lcm.subscribe("NAVD_SOLUTION", &Handler::on_solution, &handler);
  lcm.subscribe("NAVD_HEALTH", &Handler::on_health, &handler);
  const SimDir sim(12);
  SurveyProcess survey(
      {"--config", sim.config().string(), "--speed", "50"});  // config/sim.yaml's udpm URL
  const auto deadline = Clock::now() + std::chrono::seconds(20);
  while (Clock::now() < deadline && survey.wait_exit(std::chrono::milliseconds(1)) == -1) {
    lcm.handleTimeout(20);
  }
  for (int i = 0; i < 5; ++i) lcm.handleTimeout(20);
  EXPECT_GE(solutions, 5);  // 10 Hz over ~2 s
  EXPECT_GE(health, 1);
  EXPECT_GT(last.num_delayed_states, 0);
  Eigen::Matrix<double, 6, 6> cov;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) cov(r, c) = last.pose_covariance[6 * r + c];
  EXPECT_LT((cov - cov.transpose()).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(cov);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0) << cov;  // the recovered Σ_rr of the last image
  EXPECT_GT(cov(0, 0), 0.0);
  EXPECT_GT(max_cpu_percent, 0.0);  // replaying: the filter thread works
  expect_health_usage_and_innovations(last_health);
}

TEST(NavtoolSurvey, WithoutAMulticastRouteTheConfigsUdpmFallsBackToMemqWithTheFix) {
  if (!kNet.ok) GTEST_SKIP() << kNet.reason;  // namespaces: the same permission
  const SimDir sim(3);
  SurveyProcess survey({"--config", sim.config().string(), "--as-fast-as-possible"}, {}, true);
  ASSERT_EQ(survey.wait_exit(std::chrono::seconds(60)), 0) << survey.err();
  const std::string err = survey.err();
  EXPECT_NE(err.find("cannot open LCM at 'udpm://239.255.76.67:7667?ttl=0'"), std::string::npos)
      << err;
  EXPECT_NE(err.find("ip route add 224.0.0.0/4 dev lo"), std::string::npos) << err;
  EXPECT_NE(err.find("publishing in-process only (memq://)"), std::string::npos) << err;
  EXPECT_EQ(json::parse(survey.out())["images"].get<int>(), 3);  // the dive ran all the same
}

TEST(NavtoolSurvey, LcmUrlOptionThatCannotBeOpenedStopsWithTheFix) {
  if (!kNet.ok) GTEST_SKIP() << kNet.reason;
  const SimDir sim(3);
  SurveyProcess survey({"--config", sim.config().string(), "--lcm-url", kUdpmUrl}, {}, true);
  EXPECT_EQ(survey.wait_exit(std::chrono::seconds(20)), 2) << survey.err();
  EXPECT_NE(survey.err().find("ip route add 224.0.0.0/4 dev lo"), std::string::npos)
      << survey.err();
  EXPECT_TRUE(survey.out().empty()) << survey.out();
}

TEST(NavtoolSurvey, CheckpointsAreWrittenAndResumedWithCheckpointsLikeReplay) {
  const SimDir sim(8);
  sim.set_checkpoints(0.2);
  {  // paced (~3 s of dive at 20x), stopped by SIGTERM once a checkpoint is there
    SurveyProcess first({"--config", sim.config().string(), "--speed", "20", "--checkpoints"});
    const auto deadline = Clock::now() + std::chrono::seconds(30);
    while (Clock::now() < deadline && !(std::filesystem::exists(sim.checkpoints()) &&
                                        !std::filesystem::is_empty(sim.checkpoints()))) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ASSERT_EQ(::kill(first.pid(), SIGTERM), 0);
    ASSERT_EQ(first.wait_exit(std::chrono::seconds(5)), 0) << first.err();
    EXPECT_LT(json::parse(first.out())["images"].get<int>(), 8) << "ended before the SIGTERM";
  }
  SurveyProcess second(
      {"--config", sim.config().string(), "--as-fast-as-possible", "--checkpoints"});
  ASSERT_EQ(second.wait_exit(std::chrono::seconds(60)), 0) << second.err();
  EXPECT_NE(second.err().find("navd: resumed from " + sim.checkpoints().string()),
            std::string::npos)
      << second.err();
  EXPECT_EQ(json::parse(second.out())["images"].get<int>(), 8);
  // The same dive directory simulated again with other options is another input: its
  // checkpoints are not resumed.
  SurveyProcess other({"--config", sim.config().string(), "--images", "9", "--as-fast-as-possible",
                       "--checkpoints"});
  ASSERT_EQ(other.wait_exit(std::chrono::seconds(60)), 0) << other.err();
  EXPECT_EQ(other.err().find("resumed from"), std::string::npos) << other.err();
  EXPECT_NE(other.err().find("checkpoint of another input"), std::string::npos) << other.err();
  EXPECT_EQ(json::parse(other.out())["images"].get<int>(), 9);
}

}  // namespace
