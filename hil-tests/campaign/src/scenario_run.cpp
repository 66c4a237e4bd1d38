// One fault scenario end to end (fault_campaign.h): the dive played by the HIL player to the
// real navd (live, --checkpoints), an LCM listener thread recording what navd publishes, the
// host fault done on the dive's clock, then the measurements (scenario_metrics.h).
#include "scenario_run.h"

#include <signal.h>
#include <yaml-cpp/yaml.h>

#include <atomic>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <random>
#include <stdexcept>
#include <thread>

#include "host_faults.h"
#include "nav/daemon/system/host_clock.h"
#include "nav/hil/dive_player.h"

namespace nav::campaign {
namespace fs = std::filesystem;
namespace {

/// Records NAVD_SOLUTION / NAVD_HEALTH / NAVD_BOUNDS_SNAPSHOT on its own thread.
class Listener {
 public:
  explicit Listener(const std::string& url) : lcm_(url) {
    if (!lcm_.good()) throw std::runtime_error("fault campaign: cannot open LCM " + url);
    lcm_.subscribe("NAVD_SOLUTION", &Listener::on_solution, this);
    lcm_.subscribe("NAVD_HEALTH", &Listener::on_health, this);
    lcm_.subscribe("NAVD_BOUNDS_SNAPSHOT", &Listener::on_snapshot, this);
    thread_ = std::thread([this] {
      while (!stop_.load()) lcm_.handleTimeout(50);
    });
  }
  ~Listener() { stop(); }
  void stop() {
    stop_.store(true);
    if (thread_.joinable()) thread_.join();
  }
  /// Delayed states of the newest solution published before `realtime_us` (-1: none).
  int delayed_states_before(std::int64_t realtime_us) {
    std::lock_guard<std::mutex> lock(mutex_);
    int n = -1;
    for (const auto& s : rec_.solutions) {
      if (s.utime < realtime_us) n = s.num_delayed_states;
    }
    return n;
  }
  /// Delayed states of the first solution published after `realtime_us` (-1: none yet).
  int delayed_states_after(std::int64_t realtime_us) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : rec_.solutions) {
      if (s.utime > realtime_us) return s.num_delayed_states;
    }
    return -1;
  }
  /// Realtime of the first solution received after `realtime_us` (0: none).
  std::int64_t first_solution_after(std::int64_t realtime_us) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : rec_.solutions) {
      if (s.utime > realtime_us) return s.utime;
    }
    return 0;
  }
  Recording take() {
    stop();
    return std::move(rec_);
  }

 private:
  void on_solution(const lcm::ReceiveBuffer*, const std::string&, const navlcm::nav_solution_t* m) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (m->filter_status != 2) rec_.solutions.push_back(*m);
  }
  void on_health(const lcm::ReceiveBuffer*, const std::string&, const navlcm::health_t* m) {
    std::lock_guard<std::mutex> lock(mutex_);
    rec_.health.push_back(*m);
    rec_.health_received_us.push_back(daemon::realtime_us());  // this process: never offset
  }
  void on_snapshot(const lcm::ReceiveBuffer*, const std::string&,
                   const navlcm::bounds_snapshot_t* m) {
    std::lock_guard<std::mutex> lock(mutex_);
    rec_.last_snapshot = *m;
  }
  lcm::LCM lcm_;
  std::mutex mutex_;
  Recording rec_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// The player's navd config with checkpoint.path in the scenario's directory.
void write_config(const hil::DivePlayer& player, const fs::path& path, const std::string& url,
                  const fs::path& checkpoints) {
  player.write_navd_config(path, url);
  YAML::Node config = YAML::LoadFile(path.string());
  config["checkpoint"]["path"] = checkpoints.string();
  std::ofstream out(path, std::ios::trunc);
  out << config << "\n";
  if (!out) throw std::runtime_error(path.string() + ": cannot write the navd config");
}

/// navd's --clock-offset-file (wall_clock.h) holding `seconds`; "" or why not.
std::string write_clock_offset(const fs::path& path, double seconds) {
  const fs::path tmp = path.string() + ".tmp";
  { std::ofstream(tmp, std::ios::trunc) << seconds << "\n"; }
  std::error_code ec;
  fs::rename(tmp, path, ec);  // navd never reads a half-written file
  return ec ? "cannot write " + path.string() + ": " + ec.message() : std::string();
}

/// navd's exit summary line (live_mode.h: {"mode":"live",...}) from its stdout; null if none.
nlohmann::json navd_summary(const fs::path& stdout_path) {
  std::ifstream in(stdout_path);
  nlohmann::json last;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("{\"mode\":\"live\"", 0) != 0) continue;
    last = nlohmann::json::parse(line, nullptr, false);
  }
  return last.is_discarded() ? nlohmann::json() : last;
}

/// The host fault's start / end, on the main thread.
struct HostAction {
  const FaultScenario& scenario;
  const fs::path& dir;
  const fs::path& checkpoints;
  std::vector<pid_t> burners;
  std::string notes;

  void note(const std::string& what) {
    if (!what.empty()) notes += (notes.empty() ? "" : "; ") + what;
  }
  void start() {
    switch (scenario.host) {
      case HostFault::kCpuSaturation:
        burners = start_cpu_burners(2);
        note(std::to_string(burners.size()) + " spinning processes");
        break;
      case HostFault::kRouteRemoved:
        note(delete_multicast_route());
        break;
      case HostFault::kCheckpointDiskFull:
        note(fill_until_full(checkpoints / "filler"));
        break;
      case HostFault::kClockStep:
        note(write_clock_offset(dir / "clock_offset", scenario.clock_step_s));
        break;
      default:
        break;
    }
  }
  void end() {
    stop_processes(burners);
    burners.clear();
    if (scenario.host == HostFault::kRouteRemoved) note(add_multicast_route());
    if (scenario.host == HostFault::kCheckpointDiskFull) {
      std::error_code ec;
      fs::remove(checkpoints / "filler", ec);
    }
  }
};

}  // namespace

namespace {

/// navd with its arguments, restartable (kill_restart).
struct Navd {
  const ScenarioSetup& setup;
  std::vector<std::string> args;
  std::filesystem::path dir;
  pid_t pid = -1;
  void start() {
    pid = spawn_logged(setup.navd_path, args, dir);
    if (pid <= 0)
      throw std::runtime_error("fault campaign: cannot start " + setup.navd_path.string());
  }
  /// Running now? Then SIGTERM and its exit code into `out`.
  void stop(ScenarioResult& out) const {
    bool alive = false;
    (void)wait_exit_ms(pid, 0, &alive);
    out.navd_alive = alive;
    if (alive) ::kill(pid, SIGTERM);
    out.navd_exit_code = alive ? wait_exit_ms(pid, 5000) : -1;
  }
};

/// The fault's window on the dive's clock: the host action's start and end, the kill.
struct Timeline {
  const FaultScenario& scenario;
  HostAction& action;
  Navd& navd;
  Listener& listener;
  double kill_s = 0.0;
  bool started = false, ended = false, killed = false;
  std::int64_t fault_realtime_us = 0, end_realtime_us = 0, restart_realtime_us = 0;
  int states_before_kill = -1;

  void tick(double now_s) {
    if (!started && now_s >= scenario.from_s) {
      started = true;
      fault_realtime_us = daemon::realtime_us();
      action.start();
    }
    if (scenario.host == HostFault::kKillRestart && !killed && now_s >= kill_s) kill_and_restart();
    if (started && !ended && now_s >= scenario.to_s) {
      ended = true;
      end_realtime_us = daemon::realtime_us();
      action.end();
    }
  }
  void kill_and_restart() {
    killed = true;
    states_before_kill = listener.delayed_states_before(daemon::realtime_us());
    ::kill(navd.pid, SIGKILL);
    (void)wait_exit_ms(navd.pid, 2000);
    restart_realtime_us = daemon::realtime_us();
    navd.start();
    action.note("SIGKILL at dive " + std::to_string(kill_s).substr(0, 5) + " s, restarted");
  }
  /// After the run: delayed states lost, when the route's solutions came back.
  void conclude(ScenarioResult& out) {
    if (!ended) action.end();
    if (killed) {
      const int after = listener.delayed_states_after(restart_realtime_us);
      out.delayed_states_lost =
          after < 0 ? states_before_kill : std::max(0, states_before_kill - after);
      action.note("delayed states " + std::to_string(states_before_kill) + " before the kill, " +
                  std::to_string(after) + " at the first solution after the restart");
    }
    if (scenario.host == HostFault::kRouteRemoved && end_realtime_us > 0) {
      const std::int64_t back = listener.first_solution_after(end_realtime_us);
      action.note(back > 0 ? "solutions heard again " +
                                 std::to_string((back - end_realtime_us) * 1e-6).substr(0, 4) +
                                 " s after the route came back"
                           : "no solution heard after the route came back");
    }
  }
};

/// A clean scenario directory (its checkpoints on a small tmpfs for the disk-full fault).
fs::path prepare_dir(const FaultScenario& scenario, const ScenarioSetup& setup,
                     std::string& notes) {
  const fs::path dir = setup.out_dir / "scenarios" / scenario.name;
  std::error_code ec;
  fs::remove_all(dir, ec);
  fs::create_directories(dir / "checkpoints");
  if (scenario.host == HostFault::kCheckpointDiskFull) {
    notes = mount_small_tmpfs(dir / "checkpoints", 4096);
  }
  return dir;
}

void action_note(ScenarioResult& out, const std::string& what) {
  out.notes += (out.notes.empty() ? "" : "; ") + what;
}

void add_failure(ScenarioResult& out, const std::string& what) {
  out.scenario_failures += (out.scenario_failures.empty() ? "" : "; ") + what;
}

/// must_reconnect: the sensor's images / records before, during and after the window (health
/// received before the fault, before its end, last) and its reconnects; the player's images.
void check_reconnect(const FaultScenario& scenario, const Recording& rec, const Timeline& t,
                     const hil::PlayReport& report, ScenarioResult& out) {
  const auto* before = sensor_at(rec, scenario.sensor, t.fault_realtime_us);
  const auto* window_end = sensor_at(rec, scenario.sensor, t.end_realtime_us);
  const auto* last = sensor_at(rec, scenario.sensor, INT64_MAX);
  if (before == nullptr || window_end == nullptr || last == nullptr) {
    add_failure(out, scenario.sensor + " not in health before, during and after the window");
    return;
  }
  const std::int64_t during = window_end->records - before->records;
  const std::int64_t after = last->records - window_end->records;
  action_note(out, scenario.sensor + " records before / during / after: " +
                       std::to_string(before->records) + " / " + std::to_string(during) + " / " +
                       std::to_string(after) + ", reconnects " + std::to_string(last->reconnects) +
                       "; played " + std::to_string(report.camera.images) + " images, " +
                       std::to_string(report.camera.vanished) + " due while gone, " +
                       std::to_string(report.camera.sent) + " sent");
  if (!report.camera.reappear_error.empty())
    add_failure(out, "camera not restarted: " + report.camera.reappear_error);
  if (last->reconnects < 1) add_failure(out, scenario.sensor + " did not reconnect");
  if (after < 1) add_failure(out, "no " + scenario.sensor + " record after the window");
}

/// no_late_measurements: navd's exit summary (dropped_late, queue_dropped).
void check_no_late(const fs::path& dir, ScenarioResult& out) {
  const nlohmann::json summary = navd_summary(dir / "navd.stdout");
  if (!summary.contains("dropped_late") || !summary.contains("queue_dropped")) {
    add_failure(out, "no exit summary with dropped_late in navd.stdout");
    return;
  }
  const auto late = summary["dropped_late"].get<long long>();
  const auto dropped = summary["queue_dropped"].get<long long>();
  action_note(out, "navd dropped_late " + std::to_string(late) + ", queue_dropped " +
                       std::to_string(dropped));
  if (late > 0) add_failure(out, std::to_string(late) + " measurements dropped as late");
  if (dropped > 0) add_failure(out, std::to_string(dropped) + " measurements dropped (queue)");
}

/// The measurements from the recording, the CSVs, the verdict.
void measure(const FaultScenario& scenario, const ScenarioSetup& setup, const fs::path& dir,
             const TimeMap& map, std::int64_t fault_realtime_us, const Recording& rec,
             ScenarioResult& out) {
  write_health_csv(rec, dir / "health.csv");
  const TruthTrack truth(setup.dive_dir / "truth.csv");
  fill_track_metrics(rec, truth, map, scenario, out);
  write_solutions_csv(rec, truth, map, dir / "solutions.csv");
  fill_detection(rec, fault_realtime_us, scenario, out);
  out.map_xy_rms_m = map_xy_rms_m(rec, truth, map);
  judge(scenario, out);
}

}  // namespace

ScenarioResult run_scenario(const FaultScenario& scenario, const ScenarioSetup& setup) {
  ScenarioResult out;
  out.name = scenario.name;
  out.description = scenario.description;
  const fs::path dir = prepare_dir(scenario, setup, out.notes);
  const fs::path checkpoints = dir / "checkpoints";
  hil::PlayerOptions po;
  po.serial_dir = dir / "tty";
  po.reader_timeout = std::chrono::seconds(30);
  po.fake_gige_camera = setup.camera;
  po.camera_image_dir = "none";
  po.faults = scenario.player_faults;
  std::atomic<bool> mapped{false};
  TimeMap map;
  po.on_start = [&](std::int64_t dive_start_us, std::int64_t host_start_us) {
    map.dive_start_us = dive_start_us;
    map.host_start_us = host_start_us;
    map.realtime_start_us = daemon::realtime_us() - (daemon::monotonic_us() - host_start_us);
    mapped.store(true);
  };
  hil::DivePlayer player(setup.dive_dir, po);
  write_config(player, dir / "navd.yaml", setup.lcm_url, checkpoints);

  Listener listener(setup.lcm_url);
  Navd navd{setup, {"--config", (dir / "navd.yaml").string(), "--checkpoints"}, dir};
  if (scenario.host == HostFault::kClockStep) {
    navd.args.insert(navd.args.end(), {"--clock-offset-file", (dir / "clock_offset").string()});
  }
  navd.start();
  std::atomic<bool> stop_play{false}, played{false};
  hil::PlayReport report;
  std::thread play([&] {
    report = player.play(stop_play);
    played.store(true);
  });
  HostAction action{scenario, dir, checkpoints, {}, out.notes};
  Timeline timeline{scenario, action, navd, listener};
  std::mt19937_64 rng(setup.seed);
  timeline.kill_s = scenario.from_s + std::uniform_real_distribution<double>(0.0, 1.0)(rng) *
                                          (scenario.to_s - scenario.from_s);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(setup.give_up_s);
  while (!played.load() && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (mapped.load()) timeline.tick(map.dive_s(daemon::monotonic_us()));
  }
  stop_play.store(true);
  play.join();
  std::this_thread::sleep_for(std::chrono::seconds(2));  // navd's last solutions and health
  navd.stop(out);
  timeline.conclude(out);
  if (scenario.host == HostFault::kCheckpointDiskFull) action.note(unmount(checkpoints));
  const Recording rec = listener.take();
  out.player_max_late_s = report.max_late_s;
  out.notes = action.notes;
  if (!report.started) {
    out.reason = "navd never opened the played devices";
    return out;
  }
  if (scenario.must_reconnect) check_reconnect(scenario, rec, timeline, report, out);
  if (scenario.no_late_measurements) check_no_late(dir, out);
  measure(scenario, setup, dir, map, timeline.fault_realtime_us, rec, out);
  return out;
}

}  // namespace nav::campaign
