// navd sees for itself, live (config/README.md "vision"; docs/architecture.md "Vision in the
// loop"): a short simulated dive with rendered 12-bit frames (`navtool simulate
// --render-images`) is played at real time by the DivePlayer into ptys and Aravis' fake GigE
// camera, and the real navd runs live with `vision.enabled`: it writes the frames it receives
// to disk, proposes pairs on NAV_LINK_PROPOSAL, registers them on its own worker threads
// (Harris + SIFT, PCCS, LMedS, two-view refinement), answers on NAV_REGISTRATION with its run
// id and the proposal's sequence, and takes the answers back as camera links. Nobody else
// answers. Checked: every proposal is answered, >= 90 % before its deadline; links are
// accepted; the published track stays with the truth inside navd's own 3 sigma; health carries
// the vision counters. The fake camera needs a private network namespace (GVCP port 3956 on
// lo): without one the test is skipped with the reason.
//
// For the documented longer runs: NAV_HIL_VISION_IMAGES (default 6) sets the dive's image
// count, and NAV_HIL_VISION_ANSWERER=oracle answers the same proposals with the truth instead
// (support/oracle_vision.h; navd's vision off), the reference the vision run is compared with.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <navlcm/health_t.hpp>
#include <navlcm/link_proposal_t.hpp>
#include <navlcm/nav_solution_t.hpp>
#include <navlcm/registration_t.hpp>
#include <nlohmann/json.hpp>
#include <thread>

#include "../../daemon/tests/support/navd_process.h"
#include "../../daemon/tests/support/net_namespace.h"
#include "../../daemon/tests/support/udpm_probe.h"
#include "nav/hil/dive_player.h"
#include "support/background_play.h"
#include "support/oracle_vision.h"
#include "support/sim_dive.h"

namespace {

namespace fs = std::filesystem;
using nav::sim::test::file_text;
constexpr const char* kUdpmUrl = "udpm://239.255.76.67:7681?ttl=0";

/// What navd publishes, by proposal sequence where it is a pair.
struct Heard {
  std::map<std::int64_t, navlcm::link_proposal_t> proposals;
  std::map<std::int64_t, navlcm::registration_t> answers;  ///< the first answer per sequence
  std::vector<navlcm::nav_solution_t> solutions;
  std::vector<navlcm::health_t> health;
  void on_proposal(const lcm::ReceiveBuffer*, const std::string&,
                   const navlcm::link_proposal_t* m) {
    proposals.emplace(m->sequence, *m);
  }
  void on_registration(const lcm::ReceiveBuffer*, const std::string&,
                       const navlcm::registration_t* m) {
    answers.emplace(m->sequence, *m);
  }
  void on_solution(const lcm::ReceiveBuffer*, const std::string&, const navlcm::nav_solution_t* m) {
    if (m->filter_status != 2 && m->num_delayed_states > 0) solutions.push_back(*m);
  }
  void on_health(const lcm::ReceiveBuffer*, const std::string&, const navlcm::health_t* m) {
    health.push_back(*m);
  }
};

struct AnswerCounts {
  int answered = 0, in_time = 0, succeeded = 0, foreign = 0;
};

/// Answers matched to proposals: in time = available by the proposal's deadline.
AnswerCounts count_answers(const Heard& h) {
  AnswerCounts c;
  for (const auto& [sequence, a] : h.answers) {
    const auto p = h.proposals.find(sequence);
    if (p == h.proposals.end() || a.run_id != p->second.run_id ||
        a.frame_id_i != p->second.frame_id_i || a.frame_id_j != p->second.frame_id_j) {
      ++c.foreign;
      continue;
    }
    ++c.answered;
    if (a.utime <= p->second.deadline_utime) ++c.in_time;
    if (a.success) ++c.succeeded;
  }
  return c;
}

/// Worst published XY error against truth.csv (dive time from the player's mapping), and the
/// worst error over navd's own XY sigma.
struct TrackCheck {
  double max_xy_m = 0.0, max_xy_over_sigma = 0.0;
  int compared = 0;
};

TrackCheck check_track(const std::vector<navlcm::nav_solution_t>& solutions,
                       const fs::path& truth_csv, const nav::hil::PlayReport& r,
                       double late_allowance_m) {
  const auto rows = nav::sim::test::read_csv(truth_csv);
  TrackCheck c;
  for (const navlcm::nav_solution_t& s : solutions) {
    const double dive_t =
        r.dive_start_us + static_cast<double>(s.time_of_validity_us - r.host_start_us);
    if (dive_t < rows.front()[0] || dive_t > rows.back()[0]) continue;
    auto it = std::lower_bound(rows.begin(), rows.end(), dive_t,
                               [](const std::vector<double>& row, double t) { return row[0] < t; });
    const double xy = std::hypot(s.p_world_m[0] - (*it)[1], s.p_world_m[1] - (*it)[2]);
    const Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> P(s.pose_covariance);
    c.max_xy_m = std::max(c.max_xy_m, xy);
    c.max_xy_over_sigma = std::max(
        c.max_xy_over_sigma, std::max(0.0, xy - late_allowance_m) / std::sqrt(P(0, 0) + P(1, 1)));
    ++c.compared;
  }
  return c;
}

int dive_images() {
  const char* v = std::getenv("NAV_HIL_VISION_IMAGES");
  return v ? std::max(3, std::atoi(v)) : 6;
}

bool oracle_answers() {
  const char* v = std::getenv("NAV_HIL_VISION_ANSWERER");
  return v && std::string(v) == "oracle";
}

/// The player's navd config with navd's own vision stage on, two registration threads.
void enable_vision(const fs::path& navd_yaml) {
  YAML::Node root = YAML::LoadFile(navd_yaml.string());
  root["vision"]["enabled"] = true;
  root["vision"]["threads"] = 2;
  std::ofstream(navd_yaml) << root;
}

TEST(HilVisionLive, NavdRegistersItsOwnFramesAnswersInTimeAndAcceptsLinks) {
  const nav::tool::test::NetNamespace& net = nav::tool::test::isolated_network();
  if (!net.ok)
    GTEST_SKIP() << "the fake GigE camera needs a private network namespace: " << net.reason;
  const fs::path dir = nav::sim::test::scratch_dir("hil_vision_live");
  nav::sim::SimOptions so = nav::sim::test::sim_options(dir / "dive", 3, dive_images());
  so.sensor_errors.dvl_dropouts_per_hour = 0.0;
  so.render_images = true;
  const nav::sim::SimSummary sim =
      nav::sim::simulate_dive(so, nav::sim::test::sim_config_path().string());

  lcm::LCM lcm(kUdpmUrl);
  ASSERT_TRUE(lcm.good() && nav::tool::test::udpm_loops_back(lcm, "HIL_VISION_PROBE"))
      << "udpm does not loop back in the private namespace";
  Heard heard;
  lcm.subscribe("NAV_LINK_PROPOSAL", &Heard::on_proposal, &heard);
  lcm.subscribe("NAV_REGISTRATION", &Heard::on_registration, &heard);
  lcm.subscribe("NAVD_SOLUTION", &Heard::on_solution, &heard);
  lcm.subscribe("NAVD_HEALTH", &Heard::on_health, &heard);

  nav::hil::test::OracleVision oracle(
      nav::daemon::load_config_file((dir / "dive" / "config.yaml").string()),
      dir / "dive" / "truth.csv", sim.mean_altitude_m, lcm);
  if (oracle_answers())
    lcm.subscribe("NAV_LINK_PROPOSAL", &nav::hil::test::OracleVision::on_proposal, &oracle);

  nav::hil::PlayerOptions po;
  po.serial_dir = dir / "tty";
  po.camera_image_dir = dir / "frames";
  po.reader_timeout = std::chrono::seconds(20);
  po.on_start = [&](std::int64_t dive_start_us, std::int64_t host_start_us) {
    oracle.set_mapping(dive_start_us, host_start_us);
  };
  nav::hil::DivePlayer player(dir / "dive", po);
  player.write_navd_config(dir / "navd.yaml", kUdpmUrl);
  if (!oracle_answers()) enable_vision(dir / "navd.yaml");
  const pid_t navd = nav::tool::test::spawn_navd({"--config", (dir / "navd.yaml").string()}, dir);
  ASSERT_GT(navd, 0);

  nav::hil::test::BackgroundPlay play(player);
  const auto give_up =
      std::chrono::steady_clock::now() + std::chrono::seconds(40 + 10 * dive_images());
  while (!play.done() && std::chrono::steady_clock::now() < give_up) lcm.handleTimeout(20);
  const nav::hil::PlayReport report = play.finish();
  // The last image's pairs: answered within their wait (filter.registration_wait_s, 10 s).
  const auto drain = std::chrono::steady_clock::now() + std::chrono::seconds(12);
  while (std::chrono::steady_clock::now() < drain && heard.answers.size() < heard.proposals.size())
    lcm.handleTimeout(20);
  for (int i = 0; i < 60; ++i) lcm.handleTimeout(20);  // a health message after the answers

  ASSERT_EQ(nav::tool::test::wait_exit(navd, std::chrono::milliseconds(1)), -1)
      << "navd ended early: " << file_text(dir / "navd.stderr");
  ASSERT_EQ(::kill(navd, SIGTERM), 0);
  EXPECT_EQ(nav::tool::test::wait_exit(navd, std::chrono::seconds(10)), 0)
      << file_text(dir / "navd.stderr");
  const std::string out = file_text(dir / "navd.stdout");
  ASSERT_TRUE(report.started) << file_text(dir / "navd.stderr");
  const nlohmann::json summary = nlohmann::json::parse(out);

  const AnswerCounts c = count_answers(heard);
  const int proposals = static_cast<int>(heard.proposals.size());
  const double late_m = 0.6 * report.max_late_s;  // as hil_playback_test: writes late by load
  const TrackCheck track = check_track(heard.solutions, dir / "dive" / "truth.csv", report, late_m);
  std::printf(
      "%s: %d images played (%d taken by navd), %d proposals: %d answered (%d in time, %d "
      "succeeded), %d foreign; navd: %s links accepted, %s pairs expired; %d solutions: max XY "
      "error %.3f m, worst error beyond lateness / XY sigma %.2f\n",
      oracle_answers() ? "oracle" : "navd's vision", static_cast<int>(report.camera.images),
      summary["images"].get<int>(), proposals, c.answered, c.in_time, c.succeeded, c.foreign,
      summary["links_accepted"].dump().c_str(), summary["pairs_expired"].dump().c_str(),
      track.compared, track.max_xy_m, track.max_xy_over_sigma);

  EXPECT_EQ(report.camera.images, sim.images);
  ASSERT_GT(proposals, 0) << out;
  EXPECT_EQ(c.foreign, 0);
  EXPECT_EQ(c.answered, proposals) << "every proposal gets an answer";
  EXPECT_GE(c.in_time, 0.9 * proposals);
  EXPECT_GT(c.succeeded, 0);
  EXPECT_GT(summary["links_accepted"].get<int>(), 0) << out;
  ASSERT_GT(track.compared, 0);
  EXPECT_LT(track.max_xy_m, 0.25 + late_m);
  EXPECT_LT(track.max_xy_over_sigma, 3.0);
  ASSERT_FALSE(heard.health.empty());
  if (!oracle_answers()) {
    EXPECT_EQ(heard.health.back().vision_answered, c.answered);
    EXPECT_GT(heard.health.back().vision_success_rate, 0.0);
  }
  fs::remove_all(dir);
}

}  // namespace
