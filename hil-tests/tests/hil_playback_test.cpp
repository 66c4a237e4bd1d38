// Hardware-in-the-loop playback end to end (hil-tests/README.md "Playing a dive back"): a
// short simulated dive (5 images, 35 s, no DVL dropout) is played at real time by the
// DivePlayer into one pseudo-terminal per serial sensor, and the real navd binary runs in
// live mode on the config the player writes. Over LCM udpm (ttl=0, in a private network
// namespace when the kernel allows, else the host's if multicast loops back, else skipped)
// the test checks what navd publishes: NAVD_SOLUTION tracks the dive's truth.csv, its pose
// covariance is symmetric PSD, NAVD_HEALTH shows each serial sensor at its simulated rate with
// no decode error; SIGTERM stops navd within 1 s with a JSON summary. In the private namespace
// the player also serves the camera with Aravis' fake GigE camera on lo: navd then takes images
// (delayed states), recovers the robot covariance at each and publishes it (before the first
// image navd publishes a placeholder identity). Outside it the camera is not played (the
// drivers' loopback camera tests use lo's GVCP port) and the covariance check is skipped.
// Camera links (live mode, asynchronous registrations): an oracle vision stand-in
// (support/oracle_vision.h) answers navd's NAV_LINK_PROPOSAL from the truth, navd accepts
// links between its delayed states; the player also publishes the dive log's own
// NAV_REGISTRATION at their log times, on a channel navd does not read (their frame ids are the
// dive's, not those of the fake camera's frames), and the test checks them.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <navlcm/health_t.hpp>
#include <navlcm/nav_solution_t.hpp>
#include <navlcm/registration_t.hpp>
#include <nlohmann/json.hpp>
#include <thread>

#include "../../daemon/tests/support/navd_process.h"
#include "../../daemon/tests/support/net_namespace.h"
#include "../../daemon/tests/support/udpm_probe.h"
#include "nav/daemon/system/host_clock.h"
#include "nav/hil/dive_player.h"
#include "support/background_play.h"
#include "support/oracle_vision.h"
#include "support/sim_dive.h"

namespace {

namespace fs = std::filesystem;
using nav::sim::test::file_text;
constexpr const char* kUdpmUrl = "udpm://239.255.76.67:7681?ttl=0";
constexpr const char* kDiveRegistrations = "HIL_DIVE_REGISTRATION";  ///< navd does not read it

struct Received {
  std::vector<navlcm::nav_solution_t> solutions;
  std::vector<navlcm::health_t> health;
  std::vector<std::int64_t> dive_registration_utimes;
  void on_registration(const lcm::ReceiveBuffer*, const std::string&,
                       const navlcm::registration_t* m) {
    dive_registration_utimes.push_back(m->utime);
  }
  void on_solution(const lcm::ReceiveBuffer*, const std::string&, const navlcm::nav_solution_t* m) {
    if (m->filter_status != 2) solutions.push_back(*m);  // 2: initialising
  }
  void on_health(const lcm::ReceiveBuffer*, const std::string&, const navlcm::health_t* m) {
    health.push_back(*m);
  }
};

/// truth.csv rows (t_us, x, y, z, roll, pitch, heading, ...) at 20 Hz.
class Truth {
 public:
  explicit Truth(const fs::path& csv) : rows_(nav::sim::test::read_csv(csv)) {}
  /// The row nearest in time to `t_us` (50 ms apart: 2.5 cm at 0.5 m/s).
  const std::vector<double>& at(double t_us) const {
    auto it = std::lower_bound(rows_.begin(), rows_.end(), t_us,
                               [](const std::vector<double>& r, double t) { return r[0] < t; });
    if (it == rows_.end()) return rows_.back();
    if (it != rows_.begin() && t_us - (*(it - 1))[0] < (*it)[0] - t_us) --it;
    return *it;
  }

 private:
  std::vector<std::vector<double>> rows_;
};

double wrap_pi(double a) { return std::remainder(a, 2.0 * M_PI); }

struct TrackErrors {
  double horizontal_m = 0.0, depth_m = 0.0, heading_rad = 0.0, min_eigenvalue = 0.0;
  double asymmetry = 0.0;
  int compared = 0;
  int with_delayed_states = 0;  ///< solutions published after an image (a recovered covariance)
  double last_sigma_xy_m = 0.0;
  /// (XY error - what the player's lateness explains) / sqrt(var_x + var_y), after an image
  double max_xy_error_over_sigma = 0.0;
};

/// Symmetry and smallest eigenvalue of a recovered pose covariance, its XY sigma.
void add_covariance(const navlcm::nav_solution_t& s, TrackErrors& e) {
  const Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> P(s.pose_covariance);
  e.asymmetry =
      std::max(e.asymmetry, (P - P.transpose()).cwiseAbs().maxCoeff() / P.cwiseAbs().maxCoeff());
  const Eigen::Matrix<double, 6, 6> sym = 0.5 * (P + P.transpose());
  e.min_eigenvalue = std::min(
      e.min_eigenvalue,
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(sym).eigenvalues().minCoeff());
  e.last_sigma_xy_m = std::sqrt(P(0, 0) + P(1, 1));
  ++e.with_delayed_states;
}

/// Worst errors of the solutions valid during the played dive against the truth.
/// `late_allowance_m`: how far the vehicle moves while a write is late (see the test).
TrackErrors track_errors(const std::vector<navlcm::nav_solution_t>& solutions, const Truth& truth,
                         const nav::hil::PlayReport& r, double late_allowance_m) {
  TrackErrors e;
  e.min_eigenvalue = INFINITY;
  for (const navlcm::nav_solution_t& s : solutions) {
    const double dive_t =
        r.dive_start_us + static_cast<double>(s.time_of_validity_us - r.host_start_us);
    if (dive_t < r.dive_start_us || dive_t > r.dive_start_us + r.dive_span_s * 1e6) continue;
    const std::vector<double>& t = truth.at(dive_t);
    e.horizontal_m =
        std::max(e.horizontal_m, std::hypot(s.p_world_m[0] - t[1], s.p_world_m[1] - t[2]));
    e.depth_m = std::max(e.depth_m, std::abs(s.p_world_m[2] - t[3]));
    e.heading_rad = std::max(e.heading_rad, std::abs(wrap_pi(s.rph_rad[2] - t[6])));
    ++e.compared;
    if (s.num_delayed_states > 0) {
      add_covariance(s, e);
      const double xy = std::hypot(s.p_world_m[0] - t[1], s.p_world_m[1] - t[2]);
      e.max_xy_error_over_sigma = std::max(
          e.max_xy_error_over_sigma, std::max(0.0, xy - late_allowance_m) / e.last_sigma_xy_m);
    }
  }
  return e;
}

/// Per sensor: records per second between the first and last health message of the window.
std::map<std::string, double> record_rates(const std::vector<navlcm::health_t>& health,
                                           std::int64_t from_utime, std::int64_t to_utime) {
  std::vector<const navlcm::health_t*> window;
  for (const navlcm::health_t& h : health) {
    if (h.utime >= from_utime && h.utime <= to_utime) window.push_back(&h);
  }
  std::map<std::string, double> rates;
  if (window.size() < 2) return rates;
  const navlcm::health_t& a = *window.front();
  const navlcm::health_t& b = *window.back();
  const double span_s = (b.utime - a.utime) * 1e-6;
  for (const navlcm::sensor_health_t& sb : b.sensors) {
    for (const navlcm::sensor_health_t& sa : a.sensors) {
      if (sa.name == sb.name) rates[sb.name] = (sb.records - sa.records) / span_s;
    }
  }
  return rates;
}

TEST(HilPlayback, NavdOnPlayedPtysTracksTheTruthAndReportsHealthyRates) {
  const nav::tool::test::NetNamespace& net =
      nav::tool::test::isolated_network();  // before any thread
  const std::string netns_error = net.ok ? "" : net.reason;
  if (!netns_error.empty())
    std::printf("no private network namespace (%s): host network\n", netns_error.c_str());
  const fs::path dir = nav::sim::test::scratch_dir("hil_playback");
  nav::sim::SimOptions so = nav::sim::test::sim_options((dir / "dive"), 3, 5);
  so.sensor_errors.dvl_dropouts_per_hour = 0.0;  // dead reckoning all through: a pose check
  const nav::sim::SimSummary sim =
      nav::sim::simulate_dive(so, nav::sim::test::sim_config_path().string());

  lcm::LCM lcm(kUdpmUrl);
  const bool udpm = lcm.good() && nav::tool::test::udpm_loops_back(lcm, "HIL_PLAYBACK_PROBE");
  Received got;
  lcm.subscribe("NAVD_SOLUTION", &Received::on_solution, &got);
  lcm.subscribe("NAVD_HEALTH", &Received::on_health, &got);
  lcm.subscribe(kDiveRegistrations, &Received::on_registration, &got);
  nav::hil::test::OracleVision oracle(
      nav::daemon::load_config_file((dir / "dive" / "config.yaml").string()),
      dir / "dive" / "truth.csv", sim.mean_altitude_m, lcm);
  lcm.subscribe("NAV_LINK_PROPOSAL", &nav::hil::test::OracleVision::on_proposal, &oracle);

  nav::hil::PlayerOptions po;
  po.serial_dir = dir / "tty";
  po.reader_timeout = std::chrono::seconds(20);
  po.fake_gige_camera = netns_error.empty();
  std::atomic<std::int64_t> played_from_utime{0};
  po.on_start = [&](std::int64_t dive_start_us, std::int64_t host_start_us) {
    played_from_utime.store(nav::daemon::realtime_us());
    oracle.set_mapping(dive_start_us, host_start_us);
  };
  if (udpm) po.registration_lcm_url = kUdpmUrl;
  po.registration_channel = kDiveRegistrations;
  nav::hil::DivePlayer player(dir / "dive", po);
  bool camera = false;  // served by Aravis' fake GigE camera on this namespace's lo
  for (const nav::hil::PlayedSensor& s : player.sensors()) {
    if (s.type == "camera_gige") camera = s.output == nav::hil::SensorOutput::kGige;
    if (s.type == "camera_gige" && !camera)
      std::printf("camera part skipped: %s\n", s.note.c_str());
  }
  player.write_navd_config(dir / "navd.yaml", kUdpmUrl);
  const pid_t navd = nav::tool::test::spawn_navd({"--config", (dir / "navd.yaml").string()}, dir);
  ASSERT_GT(navd, 0);

  nav::hil::test::BackgroundPlay play(player);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(75);
  while (!play.done() && std::chrono::steady_clock::now() < give_up) {
    if (udpm)
      lcm.handleTimeout(20);
    else
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const std::int64_t played_to_utime = nav::daemon::realtime_us();
  const nav::hil::PlayReport report = play.finish();
  for (int i = 0; i < 10 && udpm; ++i) lcm.handleTimeout(20);

  ASSERT_EQ(nav::tool::test::wait_exit(navd, std::chrono::milliseconds(1)), -1)
      << "navd ended early: " << file_text(dir / "navd.stderr");
  const auto sent = std::chrono::steady_clock::now();
  ASSERT_EQ(::kill(navd, SIGTERM), 0);
  const int code = nav::tool::test::wait_exit(navd, std::chrono::seconds(5));
  const double stop_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - sent).count();
  const std::string out = file_text(dir / "navd.stdout"), err = file_text(dir / "navd.stderr");
  EXPECT_EQ(code, 0) << err;
  EXPECT_LT(stop_s, 1.0);
  std::printf("navd stopped %.3f s after SIGTERM: %s", stop_s, out.c_str());

  // The player: every serial message written, nothing dropped, the camera not played.
  ASSERT_TRUE(report.started) << "navd did not open the ptys: " << err;
  EXPECT_FALSE(report.stopped);
  const std::map<std::string, std::int64_t> sim_messages{
      {"dvl", sim.sensors.dvl_ensembles},
      {"heading", sim.sensors.heading_sentences + sim.sensors.attitude_sentences},
      {"depth", sim.sensors.depth_replies},
      {"altimeter", sim.sensors.altimeter_lines}};
  for (const nav::hil::PlayedSensor& s : report.sensors) {
    if (s.type == "camera_gige") continue;
    EXPECT_EQ(s.output, nav::hil::SensorOutput::kPty) << s.name;
    EXPECT_EQ(s.messages, sim_messages.at(s.name)) << s.name;
    EXPECT_EQ(s.dropped_bytes, 0) << s.name;
  }
  EXPECT_EQ(report.images_not_played + report.camera.images, sim.images);
  std::printf("played %.1f s of dive in %.1f s, worst lateness %.1f ms, %lld writes > 10 ms late\n",
              report.dive_span_s, report.wall_s, report.max_late_s * 1e3,
              static_cast<long long>(report.late_writes));

  const nlohmann::json summary = nlohmann::json::parse(out);
  EXPECT_EQ(summary["devices"].get<int>(), camera ? 5 : 4);
  // The player triggers the camera at the dive's image times only (test pattern: no rendered
  // frames); on a loaded machine the filter may not take every one (4 of 5 seen with serial
  // writes 688 ms late). hil_camera_navd_test checks the frames themselves.
  if (camera) {
    EXPECT_GT(summary["images"].get<int>(), 0) << out << err;
    EXPECT_LE(summary["images"].get<int>(), sim.images) << out << err;
  }
  EXPECT_EQ(summary["queue_dropped"].get<int>(), 0);
  EXPECT_GE(summary["measurements"].get<std::int64_t>(), sim.sensors.dvl_ensembles);
  if (!udpm)
    GTEST_SKIP() << "udpm ttl=0 does not loop back here (" << netns_error << "): LCM not checked";

  // navd dates bytes by their arrival: a write the loaded machine delayed by `max_late_s` is a
  // measurement that much late, so the tolerances grow by what the vehicle moves meanwhile
  // (|u|, |w| <= 0.5 m/s plus current, yaw rate <= 10 deg/s: hil-tests/README.md "Mission").
  const double late_m = 0.6 * report.max_late_s;
  const double late_rad = 10.0 * M_PI / 180.0 * report.max_late_s;
  const TrackErrors e =
      track_errors(got.solutions, Truth(dir / "dive" / "truth.csv"), report, late_m);
  std::printf("tolerances widened by %.3f m, %.2f deg for the worst write's lateness\n", late_m,
              late_rad * 180.0 / M_PI);
  std::printf(
      "%d solutions vs truth: max XY error %.3f m, depth %.3f m, heading %.3f deg; %d with a "
      "recovered covariance: min eigenvalue %.3g, asymmetry %.3g, last XY sigma %.3f m, max XY "
      "error beyond the lateness / sigma %.2f\n",
      e.compared, e.horizontal_m, e.depth_m, e.heading_rad * 180.0 / M_PI, e.with_delayed_states,
      e.min_eigenvalue, e.asymmetry, e.last_sigma_xy_m, e.max_xy_error_over_sigma);
  EXPECT_GE(e.compared, static_cast<int>(report.dive_span_s * 5));  // published at 10 Hz
  EXPECT_LT(e.horizontal_m, 0.25 + late_m);
  // The dive log's registrations, played at their log times.
  EXPECT_EQ(report.registrations_played, sim.registrations);
  EXPECT_EQ(static_cast<std::int64_t>(got.dive_registration_utimes.size()), sim.registrations);
  EXPECT_TRUE(
      std::is_sorted(got.dive_registration_utimes.begin(), got.dive_registration_utimes.end()));
  for (std::int64_t utime : got.dive_registration_utimes) {
    EXPECT_GE(utime, played_from_utime.load());
    EXPECT_LE(utime, played_to_utime);
  }
  std::printf(
      "links: %d proposals answered by the oracle (%d overlapping), navd: %s accepted, "
      "%s pairs answered, %s expired\n",
      oracle.answered, oracle.succeeded, summary["links_accepted"].dump().c_str(),
      summary["pairs_answered"].dump().c_str(), summary["pairs_expired"].dump().c_str());
  if (camera) {
    EXPECT_GT(oracle.answered, 0);
    EXPECT_GT(summary["pairs_answered"].get<int>(), 0) << out;
    EXPECT_GT(summary["links_accepted"].get<int>(), 0) << out;
    // As good as without links (0.034-0.036 m measured before they were accepted).
    EXPECT_LT(e.horizontal_m, 0.05 + late_m);
  }
  EXPECT_LT(e.depth_m, 0.1 + late_m);
  EXPECT_LT(e.heading_rad, 1.0 * M_PI / 180.0 + late_rad);
  if (camera) {
    EXPECT_GT(e.with_delayed_states, 0) << "no solution after an image";
    EXPECT_LT(e.asymmetry, 1e-9);
    EXPECT_GE(e.min_eigenvalue, 0.0);
    EXPECT_LT(e.max_xy_error_over_sigma, 3.0);  // the truth inside navd's own 3-sigma
  } else {
    std::printf("camera not played: the published covariance is navd's placeholder, not checked\n");
  }

  // Health: from 3 s into the playback (navd initialised) to its end.
  const auto rates = record_rates(got.health, played_from_utime + 3'000'000, played_to_utime);
  for (const auto& [name, messages] : sim_messages) {
    const double expected = messages / sim.duration_s;
    ASSERT_TRUE(rates.count(name)) << name << ": no health";
    std::printf("%s: %.2f records/s over the playback, %.2f simulated\n", name.c_str(),
                rates.at(name), expected);
    EXPECT_NEAR(rates.at(name), expected, 0.1 * expected) << name;
  }
  ASSERT_FALSE(got.health.empty());
  for (const navlcm::sensor_health_t& s : got.health.back().sensors) {
    EXPECT_EQ(s.decode_errors, 0) << s.name;
    if (sim_messages.count(s.name)) {
      EXPECT_GT(s.records, 0) << s.name;
    }
  }
  fs::remove_all(dir);
}

}  // namespace
