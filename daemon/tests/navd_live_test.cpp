// navd on the vehicle (live_mode.h): a heading/attitude sensor ($HEHDT + $PHTRO) and a
// Paroscientific depth sensor on two pseudo-terminals, no `sim` sensor. The device threads must
// feed the NavFilter (it initialises from attitude, heading and depth and publishes the robot
// on NAVD_SOLUTION over LCM udpm with ttl=0 in the test's own network namespace,
// support/net_namespace.h, skipped with the reason where namespaces are not permitted), and
// SIGTERM must stop navd within 1 s with exit status 0 and a JSON summary counting the
// measurements the filter took. registration_t published on NAV_REGISTRATION reach the filter
// thread; answers to no proposal of this run (here with no run id, as from an old answerer or
// a replayed log) are rejected and counted in the summary and in NAVD_HEALTH. With
// lcm.registration_signing, unsigned, wrongly signed and stale answers are rejected before
// (counted per reason), and a key file others can read stops navd naming the file and mode.
// With a `realtime` section the device and filter threads run under SCHED_FIFO at the
// configured priorities (read back from /proc) and memory is locked, or navd says why not.
#include <gtest/gtest.h>
#include <pty.h>
#include <sched.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Cholesky>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <navlcm/health_t.hpp>
#include <navlcm/nav_solution_t.hpp>
#include <navlcm/registration_t.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "nav/daemon/filter/registration_signature.h"
#include "nav/daemon/system/host_clock.h"
#include "nav/daemon/system/process_usage.h"
#include "support/navd_process.h"
#include "support/net_namespace.h"
#include "support/udpm_probe.h"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nav::tool::test::spawn_navd;
using nav::tool::test::wait_exit;
constexpr const char* kUdpmUrl = nav::tool::test::kIsolatedUdpmUrl;
// navd and this test in a network namespace of their own (before any thread starts).
const nav::tool::test::NetNamespace& kNet = nav::tool::test::isolated_network();
constexpr double kHeadingDeg = 41.87;  // "$HEHDT,41.87,T*25"

fs::path sim_yaml() {
  const fs::path rel = "config/sim.yaml";
  const auto beside = fs::path(__FILE__).parent_path().parent_path().parent_path();
  return fs::exists(beside / rel) ? beside / rel : rel;
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A pseudo-terminal whose slave path a sensor's transport opens; a thread writes `lines`
/// every `period` until stopped.
class PtySensor {
 public:
  PtySensor(std::string lines, std::chrono::milliseconds period) {
    char name[256] = {};
    int slave = -1;
    ok_ = ::openpty(&master_, &slave, name, nullptr, nullptr) == 0;
    if (ok_) ::close(slave);
    name_ = name;
    thread_ = std::thread([this, lines = std::move(lines), period] {
      while (ok_ && !stop_.load()) {
        (void)!::write(master_, lines.data(), lines.size());
        std::this_thread::sleep_for(period);
      }
    });
  }
  ~PtySensor() {
    stop_.store(true);
    thread_.join();
    if (master_ >= 0) ::close(master_);
  }
  bool ok() const { return ok_; }
  const std::string& name() const { return name_; }

 private:
  int master_ = -1;
  bool ok_ = false;
  std::string name_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// config/sim.yaml with its sensors replaced by the two pty sensors.
fs::path write_live_config(const fs::path& dir, const PtySensor& heading, const PtySensor& depth) {
  std::string text = slurp(sim_yaml());
  const std::size_t begin = text.find("sensors:\n");
  const std::size_t end = text.find("filter:\n");
  EXPECT_NE(begin, std::string::npos);
  EXPECT_NE(end, std::string::npos);
  const std::string sensors =
      "sensors:\n"
      "  - name: heading\n    type: heading_nmea\n"
      "    transport: {type: serial, device: " +
      heading.name() +
      ", baud: 9600}\n"
      "    noise: {roll_pitch_deg: 0.1, heading_deg: 0.1}\n    latency_ms: 20\n"
      "  - name: depth\n    type: pressure_paro\n"
      "    transport: {type: serial, device: " +
      depth.name() +
      ", baud: 9600}\n"
      "    noise: {depth_m: 0.01}\n    latency_ms: 50\n";
  text.replace(begin, end - begin, sensors);
  const fs::path path = dir / "live.yaml";
  std::ofstream(path) << text;
  return path;
}

struct Solutions {
  int count = 0;
  navlcm::health_t health{};
  void on_health(const lcm::ReceiveBuffer*, const std::string&, const navlcm::health_t* m) {
    health = *m;
  }
  navlcm::nav_solution_t first{}, last{};
  void on(const lcm::ReceiveBuffer*, const std::string&, const navlcm::nav_solution_t* m) {
    if (m->filter_status == 2) return;  // initialising
    if (count++ == 0) first = *m;
    last = *m;
  }
};

TEST(NavdLive, DeviceSensorsFeedTheFilterAndSigtermStopsWithinOneSecond) {
  const fs::path dir = fs::temp_directory_path() / ("navd_live_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  PtySensor heading("$HEHDT,41.87,T*25\r\n$PHTRO,0.03,M,0.15,B*59\r\n",
                    std::chrono::milliseconds(100));
  PtySensor depth("*000129.3918\r\n", std::chrono::milliseconds(200));  // ~10 m of seawater
  ASSERT_TRUE(heading.ok() && depth.ok()) << "openpty failed";
  const fs::path config = write_live_config(dir, heading, depth);
  lcm::LCM lcm(kNet.ok ? kUdpmUrl : "memq://");
  const bool udpm =
      kNet.ok && lcm.good() && nav::tool::test::udpm_loops_back(lcm, "NAVD_LIVE_TEST_PROBE");
  Solutions got;
  if (udpm) lcm.subscribe("NAVD_SOLUTION", &Solutions::on, &got);
  if (udpm) lcm.subscribe("NAVD_HEALTH", &Solutions::on_health, &got);
  const pid_t pid =
      spawn_navd({"--config", config.string(), "--lcm-url", udpm ? kUdpmUrl : "memq://"}, dir);
  const auto until = Clock::now() + std::chrono::milliseconds(2500);
  // Answers on NAV_REGISTRATION reach the filter thread: one pair, its duplicate, one with ids
  // out of order, one with a NaN covariance, 1.5 s in (navd subscribed long before). None
  // carries this run's id (navd proposed nothing: no camera), so all four are rejected as
  // another run's before any other check.
  const auto answer_at = Clock::now() + std::chrono::milliseconds(1500);
  bool answered = false;
  while (Clock::now() < until) {
    if (udpm)
      lcm.handleTimeout(20);
    else
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (udpm && !answered && Clock::now() >= answer_at) {
      navlcm::registration_t r{};
      r.frame_id_i = 1;
      r.frame_id_j = 2;
      r.success = true;
      for (int k = 0; k < 25; k += 6) r.covariance[k] = 1e-4;  // a valid 5x5 covariance
      lcm.publish("NAV_REGISTRATION", &r);
      lcm.publish("NAV_REGISTRATION", &r);  // duplicate
      r.frame_id_i = 2;                     // invalid: ids out of order
      lcm.publish("NAV_REGISTRATION", &r);
      r.frame_id_i = 1;
      r.frame_id_j = 3;
      r.covariance[12] = std::nan("");  // invalid: NaN covariance, never applied
      lcm.publish("NAV_REGISTRATION", &r);
      answered = true;
    }
  }
  ASSERT_EQ(wait_exit(pid, std::chrono::milliseconds(1)), -1)
      << "navd ended early: " << slurp(dir / "navd.stderr");
  const auto sent = Clock::now();
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  const int code = wait_exit(pid, std::chrono::seconds(5));
  const double stop_s = std::chrono::duration<double>(Clock::now() - sent).count();
  if (udpm) {
    while (lcm.handleTimeout(200) > 0) {
    }  // the last NAVD_HEALTH, published at stop
  }
  const std::string out = slurp(dir / "navd.stdout"), err = slurp(dir / "navd.stderr");
  fs::remove_all(dir);
  EXPECT_EQ(code, 0) << err;
  EXPECT_LT(stop_s, 1.0);
  const nlohmann::json j = nlohmann::json::parse(out);
  EXPECT_EQ(j["mode"], "live");
  EXPECT_EQ(j["devices"].get<int>(), 2);
  EXPECT_GE(j["measurements"].get<int>(), 20) << out;  // ~2 s of 10 Hz HDT + PHTRO, 5 Hz depth
  EXPECT_EQ(j["images"].get<int>(), 0);
  EXPECT_EQ(j["realtime_threads"].get<int>(), 0) << out;  // no `realtime` section: normal
  EXPECT_FALSE(j["memory_locked"].get<bool>()) << out;
  if (!udpm) {
    GTEST_SKIP() << (kNet.ok ? "udpm ttl=0 does not loop back in the test's namespace"
                             : kNet.reason)
                 << ": LCM not checked";
  }
  ASSERT_GE(got.count, 5) << err;  // 10 Hz once initialised
  EXPECT_EQ(j["registrations"].get<int>(), 4) << out;
  EXPECT_EQ(j["registrations_wrong_run"].get<int>(), 4) << out;
  EXPECT_EQ(j["registrations_duplicate"].get<int>(), 0) << out;
  EXPECT_EQ(j["registrations_invalid"].get<int>(), 0) << out;
  EXPECT_EQ(j["registrations_dropped"].get<int>(), 0) << out;
  // NAVD_HEALTH carries the same counts (its last message is published at stop).
  EXPECT_EQ(got.health.registrations_received, 4) << out;
  EXPECT_EQ(got.health.registrations_wrong_run, 4) << out;
  EXPECT_EQ(got.health.registrations_invalid, 0) << out;
  EXPECT_NEAR(got.last.rph_rad[2], kHeadingDeg * M_PI / 180.0, 0.01);
  EXPECT_NEAR(got.last.p_world_m[2], 10.0, 0.5);
  EXPECT_NEAR(got.last.p_world_m[0], 0.0, 0.5);  // no velocity sensor: it stays at the origin
  // The first solution (no image yet) carries the robot's marginal (Λ_rr⁻¹), not
  // an identity placeholder: symmetric positive definite, heading and depth at the size of
  // the filter's prior (10 x the sensor sigmas) or tighter.
  const Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> P(got.first.pose_covariance);
  EXPECT_LE((P - P.transpose()).norm(), 1e-12 * P.norm()) << P;
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> cholesky(P);
  EXPECT_EQ(cholesky.info(), Eigen::Success) << P;
  EXPECT_LT(std::sqrt(P(5, 5)), 2.0 * M_PI / 180.0) << P;  // heading sigma
  EXPECT_LT(std::sqrt(P(2, 2)), 0.5) << P;                 // depth sigma
}

/// comm -> (policy, real-time priority) of every thread of `pid`, from /proc/<pid>/task/*/stat
/// (proc(5): rt_priority and policy are fields 40 and 41, counted after the last ')').
std::map<std::string, std::pair<int, int>> thread_policies(pid_t pid) {
  std::map<std::string, std::pair<int, int>> out;
  for (const auto& task : fs::directory_iterator("/proc/" + std::to_string(pid) + "/task")) {
    std::string comm = slurp(task.path() / "comm"), stat = slurp(task.path() / "stat");
    if (!comm.empty() && comm.back() == '\n') comm.pop_back();
    std::istringstream fields(stat.substr(stat.rfind(')') + 2));
    std::vector<std::string> f{std::istream_iterator<std::string>(fields), {}};
    if (f.size() >= 39) out[comm] = {std::stoi(f[38]), std::stoi(f[37])};  // fields 41, 40
  }
  return out;
}

TEST(NavdLive, RealtimeSettingsRunDeviceAndFilterThreadsUnderFifoAndLockMemory) {
  const fs::path dir = fs::temp_directory_path() / ("navd_rt_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  PtySensor heading("$HEHDT,41.87,T*25\r\n$PHTRO,0.03,M,0.15,B*59\r\n",
                    std::chrono::milliseconds(100));
  PtySensor depth("*000129.3918\r\n", std::chrono::milliseconds(200));
  ASSERT_TRUE(heading.ok() && depth.ok()) << "openpty failed";
  const fs::path config = dir / "rt.yaml";
  std::ofstream(config)
      << slurp(write_live_config(dir, heading, depth))
      << "realtime: {device_priority: 40, filter_priority: 30, lock_memory: true}\n";
  const pid_t pid = spawn_navd({"--config", config.string(), "--lcm-url", "memq://"}, dir);
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const auto threads = thread_policies(pid);
  const std::string status = slurp("/proc/" + std::to_string(pid) + "/status");
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  EXPECT_EQ(wait_exit(pid, std::chrono::seconds(5)), 0);
  const std::string out = slurp(dir / "navd.stdout"), err = slurp(dir / "navd.stderr");
  fs::remove_all(dir);
  const nlohmann::json j = nlohmann::json::parse(out);
  EXPECT_GE(j["measurements"].get<int>(), 10) << out;  // navigating either way
  for (const char* name : {"navd-heading", "navd-depth", "navd-filter", "navd-publisher"}) {
    ASSERT_TRUE(threads.count(name)) << name << " not among navd's threads";
  }
  EXPECT_EQ(threads.at("navd-publisher"), std::make_pair(SCHED_OTHER, 0));
  const std::optional<double> locked_kb = nav::daemon::parse_proc_status_kb(status, "VmLck");
  ASSERT_TRUE(locked_kb.has_value()) << status;
  std::printf("navd: VmLck %.0f kB, VmRSS %.0f kB\n", *locked_kb,
              nav::daemon::parse_proc_status_kb(status, "VmRSS").value_or(-1.0));
  EXPECT_EQ(j["memory_locked"].get<bool>(), *locked_kb > 0) << status;
  if (j["realtime_refused"].get<int>() > 0) {
    // The kernel refused (no CAP_SYS_NICE, RLIMIT_RTPRIO too low): navd says why and runs on.
    EXPECT_EQ(j["realtime_refused"].get<int>(), 3) << out;
    EXPECT_NE(err.find("keeps normal scheduling: SCHED_FIFO priority"), std::string::npos) << err;
    EXPECT_EQ(threads.at("navd-filter"), std::make_pair(SCHED_OTHER, 0));
    GTEST_SKIP() << "SCHED_FIFO refused here: the refusal path was checked";
  }
  EXPECT_EQ(j["realtime_threads"].get<int>(), 3) << out;
  EXPECT_EQ(threads.at("navd-heading"), std::make_pair(SCHED_FIFO, 40));
  EXPECT_EQ(threads.at("navd-depth"), std::make_pair(SCHED_FIFO, 40));
  EXPECT_EQ(threads.at("navd-filter"), std::make_pair(SCHED_FIFO, 30));
  EXPECT_TRUE(j["memory_locked"].get<bool>()) << err;
}

constexpr const char* kKeyHex = "8f0e3c2b1a09f8e7d6c5b4a3928170615f4e3d2c1b0a9f8e7d6c5b4a39281706";

/// `config` with lcm.registration_signing naming `key_file` (2 s window).
fs::path with_signing(const fs::path& config, const fs::path& key_file) {
  std::string text = slurp(config);
  const std::size_t lcm = text.find("lcm:\n");
  EXPECT_NE(lcm, std::string::npos);
  text.insert(lcm + 5, "  registration_signing: {key_file: " + key_file.string() +
                           ", window_s: 2}\n");
  const fs::path path = config.parent_path() / "signed.yaml";
  std::ofstream(path) << text;
  return path;
}

TEST(NavdLive, SigningRejectsUnsignedForgedAndStaleAnswersAndAnOpenKeyFile) {
  const fs::path dir = fs::temp_directory_path() / ("navd_sign_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  PtySensor heading("$HEHDT,41.87,T*25\r\n", std::chrono::milliseconds(100));
  PtySensor depth("*000129.3918\r\n", std::chrono::milliseconds(200));
  ASSERT_TRUE(heading.ok() && depth.ok()) << "openpty failed";
  const fs::path key_file = dir / "registration.key";
  std::ofstream(key_file) << kKeyHex << "\n";
  ASSERT_EQ(::chmod(key_file.c_str(), 0644), 0);
  const fs::path config = with_signing(write_live_config(dir, heading, depth), key_file);
  // A key file others can read: navd refuses to start, naming the file and its mode.
  pid_t pid = spawn_navd({"--config", config.string(), "--lcm-url", "memq://"}, dir);
  EXPECT_EQ(wait_exit(pid, std::chrono::seconds(5)), 1);
  const std::string refused = slurp(dir / "navd.stderr");
  EXPECT_NE(refused.find(key_file.string()), std::string::npos) << refused;
  EXPECT_NE(refused.find("0644"), std::string::npos) << refused;
  ASSERT_EQ(::chmod(key_file.c_str(), 0600), 0);

  lcm::LCM lcm(kNet.ok ? kUdpmUrl : "memq://");
  if (!kNet.ok || !lcm.good() || !nav::tool::test::udpm_loops_back(lcm, "NAVD_SIGN_PROBE")) {
    fs::remove_all(dir);
    GTEST_SKIP() << "udpm ttl=0 not available here: signed answers not checked";
  }
  Solutions got;
  lcm.subscribe("NAVD_HEALTH", &Solutions::on_health, &got);
  pid = spawn_navd({"--config", config.string(), "--lcm-url", kUdpmUrl}, dir);
  const nav::daemon::SigningKey key = nav::daemon::signing_key_from_hex(kKeyHex);
  const auto until = Clock::now() + std::chrono::milliseconds(2000);
  const auto answer_at = Clock::now() + std::chrono::milliseconds(1000);
  bool answered = false;
  while (Clock::now() < until) {
    lcm.handleTimeout(20);
    if (answered || Clock::now() < answer_at) continue;
    navlcm::registration_t r{};
    r.frame_id_i = 1;
    r.frame_id_j = 2;
    r.success = true;
    for (int k = 0; k < 25; k += 6) r.covariance[k] = 1e-4;
    lcm.publish("NAV_REGISTRATION", &r);  // unsigned
    const std::int64_t now = nav::daemon::realtime_us();
    nav::daemon::sign_registration(r, key, 7, now - 10'000'000);  // 10 s old: stale
    lcm.publish("NAV_REGISTRATION", &r);
    nav::daemon::sign_registration(r, nav::daemon::signing_key_from_hex(std::string(64, 'f')), 7,
                                   now);  // another key
    lcm.publish("NAV_REGISTRATION", &r);
    nav::daemon::sign_registration(r, key, 7, now);  // valid, but no proposal of this run
    lcm.publish("NAV_REGISTRATION", &r);
    lcm.publish("NAV_REGISTRATION", &r);  // the same again: stale (not after signer 7's last)
    answered = true;
  }
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  EXPECT_EQ(wait_exit(pid, std::chrono::seconds(5)), 0) << slurp(dir / "navd.stderr");
  while (lcm.handleTimeout(200) > 0) {
  }  // the last NAVD_HEALTH, published at stop
  const std::string out = slurp(dir / "navd.stdout");
  fs::remove_all(dir);
  const nlohmann::json j = nlohmann::json::parse(out);
  EXPECT_EQ(j["registrations_unsigned"].get<int>(), 1) << out;
  EXPECT_EQ(j["registrations_stale_signature"].get<int>(), 2) << out;
  EXPECT_EQ(j["registrations_bad_signature"].get<int>(), 1) << out;
  EXPECT_EQ(j["registrations_wrong_run"].get<int>(), 1) << out;
  EXPECT_EQ(j["registrations"].get<int>(), 1) << out;  // only the valid one was queued
  EXPECT_EQ(got.health.registrations_received, 5);
  EXPECT_EQ(got.health.registrations_unsigned, 1);
  EXPECT_EQ(got.health.registrations_stale_signature, 2);
  EXPECT_EQ(got.health.registrations_bad_signature, 1);
  EXPECT_EQ(got.health.registrations_wrong_run, 1);
}

}  // namespace
