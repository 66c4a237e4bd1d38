// The soak: navd live on a dive played back to back, its resources sampled; see soak.h.
#include "nav/campaign/soak.h"

#include <signal.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <navlcm/health_t.hpp>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "campaign_dive.h"
#include "host_faults.h"
#include "nav/daemon/system/host_clock.h"
#include "nav/hil/dive_player.h"
#include "soak_analysis.h"

namespace nav::campaign {
namespace fs = std::filesystem;
namespace {

/// The newest NAVD_HEALTH's queue depth, drops and late measurements (summed over sensors).
class HealthWatch {
 public:
  explicit HealthWatch(const std::string& url) : lcm_(url) {
    if (!lcm_.good()) throw std::runtime_error("soak: cannot open LCM " + url);
    lcm_.subscribe("NAVD_HEALTH", &HealthWatch::on_health, this);
    thread_ = std::thread([this] {
      while (!stop_.load()) lcm_.handleTimeout(50);
    });
  }
  ~HealthWatch() {
    stop_.store(true);
    thread_.join();
  }
  void fill(SoakSample& s) {
    std::lock_guard<std::mutex> lock(mutex_);
    s.queue_depth = queue_depth_;
    s.queue_drops = queue_drops_;
    s.late_measurements = late_;
  }

 private:
  void on_health(const lcm::ReceiveBuffer*, const std::string&, const navlcm::health_t* m) {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_depth_ = m->queue_depth;
    queue_drops_ = late_ = 0;
    for (const navlcm::sensor_health_t& s : m->sensors) {
      queue_drops_ += s.queue_drops;
      late_ += s.late_measurements;
    }
  }
  lcm::LCM lcm_;
  std::mutex mutex_;
  int queue_depth_ = 0;
  std::int64_t queue_drops_ = 0, late_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// VmRSS (MiB), utime + stime (s) and open descriptors of `pid` from /proc; false if gone.
bool sample_process(pid_t pid, SoakSample& s) {
  const std::string proc = "/proc/" + std::to_string(pid);
  std::ifstream status(proc + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) s.rss_mb = std::stod(line.substr(6)) / 1024.0;
  }
  std::ifstream stat(proc + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  const std::size_t close = text.rfind(')');  // comm may hold spaces
  if (close == std::string::npos) return false;
  std::stringstream fields(text.substr(close + 2));
  std::string f;
  double utime = 0, stime = 0;
  for (int i = 3; i <= 15 && fields >> f; ++i) {  // field 3 is the state
    if (i == 14) utime = std::stod(f);
    if (i == 15) stime = std::stod(f);
  }
  s.cpu_s = (utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
  std::error_code ec;
  s.fds = static_cast<int>(
      std::distance(fs::directory_iterator(proc + "/fd", ec), fs::directory_iterator()));
  return !ec && s.rss_mb > 0.0;
}

void write_config(const hil::DivePlayer& player, const fs::path& path, const std::string& url,
                  const fs::path& checkpoints) {
  player.write_navd_config(path, url);
  YAML::Node config = YAML::LoadFile(path.string());
  config["checkpoint"]["path"] = checkpoints.string();
  std::ofstream out(path, std::ios::trunc);
  out << config << "\n";
  if (!out) throw std::runtime_error(path.string() + ": cannot write the navd config");
}

}  // namespace

SoakSummary run_soak(const SoakOptions& o) {
  fs::create_directories(o.out_dir / "checkpoints");
  if (std::string e = enter_private_namespaces(); !e.empty()) {
    std::fprintf(stderr, "soak: no private namespace (%s): host network\n", e.c_str());
  }
  const fs::path dive =
      simulated_dive(o.out_dir / "dive", o.dive_images, o.seed, o.sim_config, true);
  hil::PlayerOptions po;
  po.speed = o.speed;
  po.repeat = o.passes;
  po.fake_gige_camera = false;
  po.serial_dir = o.out_dir / "tty";
  po.camera_image_dir = "none";
  po.reader_timeout = std::chrono::seconds(30);
  std::atomic<std::int64_t> host_start_us{0};
  po.on_start = [&](std::int64_t, std::int64_t host_us) { host_start_us.store(host_us); };
  hil::DivePlayer player(dive, po);
  write_config(player, o.out_dir / "navd.yaml", o.lcm_url, o.out_dir / "checkpoints");
  HealthWatch health(o.lcm_url);
  const pid_t navd = spawn_logged(
      o.navd_path, {"--config", (o.out_dir / "navd.yaml").string(), "--checkpoints"}, o.out_dir);
  if (navd <= 0) throw std::runtime_error("soak: cannot start " + o.navd_path.string());
  std::atomic<bool> stop{false}, done{false};
  hil::PlayReport report;
  std::thread play([&] {
    report = player.play(stop);
    done.store(true);
  });
  std::vector<SoakSample> samples;
  std::ofstream csv(o.out_dir / "soak.csv", std::ios::trunc);
  csv << "wall_s,dive_h,rss_mb,cpu_s,fds,queue_depth,queue_drops,late_measurements\n";
  const std::int64_t wall_start_us = daemon::monotonic_us();
  while (!done.load()) {
    daemon::sleep_until_monotonic_us(
        daemon::monotonic_us() + static_cast<std::int64_t>(o.sample_period_s * 1e6), done);
    if (host_start_us.load() == 0) continue;
    SoakSample s;
    s.wall_s = (daemon::monotonic_us() - wall_start_us) * 1e-6;
    s.dive_h = (daemon::monotonic_us() - host_start_us.load()) * 1e-6 * o.speed / 3600.0;
    if (!sample_process(navd, s)) break;  // navd gone
    health.fill(s);
    samples.push_back(s);
    csv << s.wall_s << "," << s.dive_h << "," << s.rss_mb << "," << s.cpu_s << "," << s.fds << ","
        << s.queue_depth << "," << s.queue_drops << "," << s.late_measurements << std::endl;
  }
  stop.store(true);
  play.join();
  SoakSummary summary = analyse_soak(samples, o.warmup_dive_h);
  bool alive = false;
  (void)wait_exit_ms(navd, 0, &alive);
  summary.navd_alive = alive;
  if (alive) ::kill(navd, SIGTERM);
  summary.navd_exit_code = alive ? wait_exit_ms(navd, 10000) : -1;
  std::ifstream navd_out(o.out_dir / "navd.stdout");
  std::getline(navd_out, summary.navd_summary);
  plot_soak(samples, summary, o.out_dir);
  std::ofstream(o.out_dir / "soak.json", std::ios::trunc) << soak_json(summary).dump(2) << "\n";
  return summary;
}

nlohmann::json soak_json(const SoakSummary& s) {
  return {{"dive_hours", s.dive_hours},
          {"wall_s", s.wall_s},
          {"samples", s.samples},
          {"rss_first_mb", s.rss_first_mb},
          {"rss_last_mb", s.rss_last_mb},
          {"rss_slope_mb_per_dive_h", s.rss_slope_mb_per_dive_h},
          {"rss_growth_percent", s.rss_growth_percent},
          {"cpu_s_per_dive_h", s.cpu_s_per_dive_h},
          {"cpu_slope_per_dive_h", s.cpu_slope_per_dive_h},
          {"fds_min", s.fds_min},
          {"fds_max", s.fds_max},
          {"max_queue_depth", s.max_queue_depth},
          {"queue_drops", s.queue_drops},
          {"late_measurements", s.late_measurements},
          {"navd_alive", s.navd_alive},
          {"navd_exit_code", s.navd_exit_code},
          {"navd_summary", s.navd_summary}};
}

}  // namespace nav::campaign
