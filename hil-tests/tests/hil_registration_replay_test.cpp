// Provenance of registrations end to end (docs/formats.md "Provenance of registrations"): the
// accident it guards against is an operator replaying an earlier dive's LCM log with
// lcm-logplayer while navd runs, whose registration_t name the same frame ids as today's.
// A 3-image dive (seed 3, ~19 s) is played twice at real time by DivePlayer in the test's own
// user + network namespace (ptys, Aravis' fake GigE camera on lo) into the real navd in live
// mode, an oracle vision stand-in (support/oracle_vision.h) answering navd's proposals:
// 1. run 1: lcm-logger records NAV_REGISTRATION (the oracle's answers, run 1's id);
// 2. run 2: lcm-logplayer plays that log on the same LCM URL meanwhile.
// Asserted for run 2: every replayed answer is rejected as another run's (health_t and the
// JSON line at exit count exactly the log's registrations), none is inserted, and the map's
// links come from run 2's own oracle only: navd inserted no more answers than the oracle sent,
// applied only inserted ones, waited for every proposal the oracle saw, and accepted links.
// Two live runs are not byte-identical (host timing), so the map is compared through what
// reaches the registration table: nothing but run 2's own answers. Skipped with the reason
// where the namespace or udpm loopback is not available.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>

#include <atomic>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/health_t.hpp>
#include <navlcm/link_proposal_t.hpp>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "../../daemon/tests/support/navd_process.h"
#include "../../daemon/tests/support/net_namespace.h"
#include "../../daemon/tests/support/udpm_probe.h"
#include "nav/hil/dive_player.h"
#include "support/background_play.h"
#include "support/oracle_vision.h"
#include "support/sim_dive.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using nav::sim::test::file_text;
constexpr const char* kUdpmUrl = "udpm://239.255.76.67:7689?ttl=0";
const auto* const kCleanup =
    ::testing::AddGlobalTestEnvironment(new nav::sim::test::ScratchCleanup);

/// A helper process (lcm-logger, lcm-logplayer) from PATH; -1 when it cannot start.
pid_t spawn(const std::vector<std::string>& args) {
  std::vector<char*> argv;
  std::vector<std::string> copy = args;
  for (std::string& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  return ::posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ) == 0 ? pid : -1;
}

struct LiveRun {
  nlohmann::json summary;
  navlcm::health_t last_health{};
  int health_messages = 0;
  int oracle_answered = 0, oracle_proposals = 0;
  std::string err;
  int code = -1;
  std::set<std::pair<std::int64_t, std::int64_t>> proposed_pairs;
  void on_health(const lcm::ReceiveBuffer*, const std::string&, const navlcm::health_t* m) {
    last_health = *m;
    ++health_messages;
  }
  void on_proposal(const lcm::ReceiveBuffer*, const std::string&,
                   const navlcm::link_proposal_t* m) {
    proposed_pairs.insert({m->frame_id_i, m->frame_id_j});
  }
};

/// One live run of the dive in `dir`/dive with the oracle answering; `during` is started when
/// the player starts (navd has opened its devices, so it listens; a logger or a log player). A log
/// player is waited for (up to 15 s) before navd stops, so all of its log reaches navd; a logger is
/// stopped (SIGINT) after navd.
LiveRun run_live(const fs::path& dir, const std::string& name,
                 const std::vector<std::string>& during, bool wait_for_helper) {
  LiveRun run;
  const fs::path run_dir = dir / name;
  fs::create_directories(run_dir);
  lcm::LCM lcm(kUdpmUrl);
  lcm.subscribe("NAVD_HEALTH", &LiveRun::on_health, &run);
  lcm.subscribe("NAV_LINK_PROPOSAL", &LiveRun::on_proposal, &run);
  nav::hil::test::OracleVision oracle(
      nav::daemon::load_config_file((dir / "dive" / "config.yaml").string()),
      dir / "dive" / "truth.csv", 3.0, lcm);
  lcm.subscribe("NAV_LINK_PROPOSAL", &nav::hil::test::OracleVision::on_proposal, &oracle);
  nav::hil::PlayerOptions po;
  po.serial_dir = run_dir / "tty";
  po.reader_timeout = std::chrono::seconds(20);
  std::atomic<bool> started{false};
  po.on_start = [&](std::int64_t dive_start_us, std::int64_t host_start_us) {
    oracle.set_mapping(dive_start_us, host_start_us);
    started.store(true);
  };
  nav::hil::DivePlayer player(dir / "dive", po);
  player.write_navd_config(run_dir / "navd.yaml", kUdpmUrl);
  const pid_t navd =
      nav::tool::test::spawn_navd({"--config", (run_dir / "navd.yaml").string()}, run_dir);
  EXPECT_GT(navd, 0);
  pid_t helper = 0;
  nav::hil::test::BackgroundPlay play(player);
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(50);
  while (!play.done() && std::chrono::steady_clock::now() < give_up) {
    lcm.handleTimeout(20);
    if (helper == 0 && started.load()) {
      helper = spawn(during);
      EXPECT_GT(helper, 0) << during.front() << " did not start";
    }
  }
  (void)play.finish();
  for (int i = 0; i < 25; ++i) lcm.handleTimeout(20);  // the last answers
  if (helper > 0 && wait_for_helper) {
    EXPECT_EQ(nav::tool::test::wait_exit(helper, std::chrono::seconds(15)), 0) << during.front();
    for (int i = 0; i < 25; ++i) lcm.handleTimeout(20);
  }
  ::kill(navd, SIGTERM);
  run.code = nav::tool::test::wait_exit(navd, std::chrono::seconds(5));
  while (lcm.handleTimeout(200) > 0) {
  }  // navd's last NAVD_HEALTH, published at stop
  if (helper > 0 && !wait_for_helper) {
    ::kill(helper, SIGINT);
    nav::tool::test::wait_exit(helper, std::chrono::seconds(5));
  }
  run.err = file_text(run_dir / "navd.stderr");
  const std::string out = file_text(run_dir / "navd.stdout");
  run.summary = nlohmann::json::parse(out.empty() ? "{}" : out);
  run.oracle_answered = oracle.answered;
  run.oracle_proposals = oracle.proposals;
  return run;
}

struct Logged {
  int count = 0;
  std::set<std::int64_t> run_ids;
  std::set<std::pair<std::int64_t, std::int64_t>> pairs;
};

/// The NAV_REGISTRATION events in an LCM log file.
Logged logged_registrations(const fs::path& file) {
  lcm::LogFile log(file.string(), "r");
  Logged out;
  if (!log.good()) return out;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != "NAV_REGISTRATION") continue;
    navlcm::registration_t r;
    if (r.decode(e->data, 0, static_cast<int>(e->datalen)) < 0) continue;
    ++out.count;
    out.run_ids.insert(r.run_id);
    out.pairs.insert({r.frame_id_i, r.frame_id_j});
  }
  return out;
}

TEST(HilRegistrationReplay, AnswersReplayedFromAnEarlierRunNeverReachTheMap) {
  const nav::tool::test::NetNamespace& net = nav::tool::test::isolated_network();
  if (!net.ok) GTEST_SKIP() << "no private network namespace: " << net.reason;
  const fs::path dir = nav::sim::test::scratch_dir("hil_registration_replay");
  nav::sim::simulate_dive(nav::sim::test::sim_options(dir / "dive", 3, 3),
                          nav::sim::test::sim_config_path().string());
  {
    lcm::LCM probe(kUdpmUrl);
    if (!probe.good() || !nav::tool::test::udpm_loops_back(probe, "HIL_REPLAY_PROBE"))
      GTEST_SKIP() << "udpm ttl=0 does not loop back in the namespace";
  }
  const fs::path log = dir / "run1.lcmlog";
  const LiveRun first = run_live(dir, "run1",
                                 {"lcm-logger", "-q", "-f", "--lcm-url=" + std::string(kUdpmUrl),
                                  "--channel=NAV_REGISTRATION", log.string()},
                                 false);
  ASSERT_EQ(first.code, 0) << first.err;
  const Logged recorded = logged_registrations(log);
  const int logged = recorded.count;
  ASSERT_GT(logged, 0) << "run 1 recorded no registration: " << first.summary.dump();
  EXPECT_EQ(logged, first.oracle_answered);
  EXPECT_EQ(recorded.run_ids.size(), 1u);  // one navd run, one id
  EXPECT_GT(first.summary["links_accepted"].get<int>(), 0) << first.summary.dump();

  const LiveRun second = run_live(
      dir, "run2", {"lcm-logplayer", "--lcm-url=" + std::string(kUdpmUrl), log.string()}, true);
  ASSERT_EQ(second.code, 0) << second.err;
  const nlohmann::json& s = second.summary;
  // The hazard is real: the replayed answers name pairs that run 2 proposed too (same frame
  // ids), so frame ids alone would have let them into run 2's map.
  int colliding = 0;
  for (const auto& pair : recorded.pairs) colliding += second.proposed_pairs.count(pair) ? 1 : 0;
  EXPECT_GT(colliding, 0);
  std::printf("run 1: %d answers logged; run 2: %s\n", logged, s.dump().c_str());
  // Every replayed answer rejected as another run's, counted in health_t and at exit.
  EXPECT_EQ(s["registrations_wrong_run"].get<int>(), logged) << s.dump();
  EXPECT_EQ(second.last_health.registrations_wrong_run, logged);
  EXPECT_EQ(second.last_health.registrations_received, logged + second.oracle_answered);
  for (const char* reason : {"registrations_unknown_sequence", "registrations_already_answered",
                             "registrations_pair_mismatch", "registrations_invalid",
                             "registrations_duplicate", "registrations_dropped"}) {
    EXPECT_EQ(s[reason].get<int>(), 0) << reason << ": " << s.dump();
  }
  // What reached the table: run 2's own answers only.
  EXPECT_GT(second.oracle_answered, 0);
  EXPECT_EQ(s["registrations"].get<int>(), logged + second.oracle_answered);
  EXPECT_GT(s["registrations_inserted"].get<int>(), 0) << s.dump();
  EXPECT_LE(s["registrations_inserted"].get<int>(), second.oracle_answered) << s.dump();
  EXPECT_LE(s["pairs_answered"].get<int>(), s["registrations_inserted"].get<int>()) << s.dump();
  EXPECT_EQ(s["pairs_deferred"].get<int>(), second.oracle_proposals) << s.dump();
  EXPECT_GT(s["links_accepted"].get<int>(), 0) << s.dump();
  fs::remove_all(dir);
}

}  // namespace
