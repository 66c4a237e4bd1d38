// NavFilter with asynchronous registrations (nav/core/navigation/pending_registrations.h): a
// registration available at the image is used there; one arriving later is applied between the
// two delayed states; unanswered pairs expire; the pending set is bounded; and a table filled
// while the filter runs (live mode: RegistrationInbox, registration_inbox.h) gives exactly the
// links of a table filled before (replay) for the same registration arrival times.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "nav/core/navigation/nav_filter.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/queue/registration_inbox.h"
#include "support/synthetic_dive.h"

namespace nav::daemon {
namespace {

using nav::testing::SyntheticDive;

NavdConfig sim_config() { return nav::testing::synthetic_dive_config(); }

/// The dive with receive times: host_realtime_us = validity_us + 5e12 (another clock).
constexpr std::int64_t kRealtimeOffsetUs = 5'000'000'000'000;

SyntheticDive dive_with_realtime() {
  nav::testing::SyntheticDiveOptions o;
  o.duration_s = 120.0;
  SyntheticDive dive = nav::testing::make_synthetic_dive(sim_config(), o);
  for (Measurement& m : dive.measurements) {
    std::visit([](auto& x) { x.time.host_realtime_us = x.time.validity_us + kRealtimeOffsetUs; },
               m);
  }
  return dive;
}

/// Registration utimes: image j's receive time + a delay of 0.5 to 4.5 s (varies by pair).
std::vector<navlcm::registration_t> delayed(const SyntheticDive& dive) {
  std::vector<navlcm::registration_t> out = dive.registration_messages;
  for (navlcm::registration_t& r : out) {
    const std::int64_t delay_us = 500'000 + ((r.frame_id_i * 7 + r.frame_id_j) % 9) * 500'000;
    r.utime =
        dive.image_t_us[static_cast<std::size_t>(r.frame_id_j)] + kRealtimeOffsetUs + delay_us;
  }
  return out;
}

NavFilterOptions async_options(double wait_s, int max_pending = 256) {
  NavFilterOptions o = filter_options_from_config(sim_config());
  o.registration_wait_s = wait_s;
  o.max_pending_registrations = max_pending;
  return o;
}

/// Replay style: every registration in the table before the first measurement.
std::unique_ptr<NavFilter> run_replay(const SyntheticDive& dive, const RegistrationTable& table,
                                      const NavFilterOptions& options) {
  auto f = std::make_unique<NavFilter>(options, &table);
  for (const Measurement& m : dive.measurements) EXPECT_TRUE(f->process(m).ok());
  EXPECT_TRUE(f->finish().ok());
  return f;
}

RegistrationTable table_of(const std::vector<navlcm::registration_t>& regs) {
  RegistrationTable t;
  for (const auto& r : regs) t.insert(registration_from_message(r));
  return t;
}

void expect_same_links(const NavFilter& a, const NavFilter& b) {
  ASSERT_EQ(a.links().size(), b.links().size());
  for (std::size_t k = 0; k < a.links().size(); ++k) {
    const LinkRecord& x = a.links()[k];
    const LinkRecord& y = b.links()[k];
    EXPECT_EQ(x.frame_i, y.frame_i) << "row " << k;
    EXPECT_EQ(x.frame_j, y.frame_j) << "row " << k;
    EXPECT_EQ(x.t_us, y.t_us) << "row " << k;
    EXPECT_EQ(x.state_i, y.state_i) << "row " << k;
    EXPECT_EQ(x.state_j, y.state_j) << "row " << k;
    EXPECT_EQ(x.outcome, y.outcome) << "row " << k;
    EXPECT_EQ(x.mahalanobis_sq, y.mahalanobis_sq) << "row " << k;
  }
  EXPECT_EQ(a.esdf().mean(), b.esdf().mean());
}

std::size_t accepted(const NavFilter& f) {
  return static_cast<std::size_t>(
      std::count_if(f.links().begin(), f.links().end(),
                    [](const auto& l) { return l.outcome == LinkOutcome::kAccepted; }));
}

TEST(AsyncLinks, RegistrationAvailableAtTheImageIsUsedThereAsWithoutWaiting) {
  const SyntheticDive dive = dive_with_realtime();
  std::vector<navlcm::registration_t> regs = dive.registration_messages;
  for (auto& r : regs) r.utime += kRealtimeOffsetUs;  // available at image j's receive time
  const RegistrationTable table = table_of(regs);
  const auto sync = run_replay(dive, table, async_options(0.0));
  const auto async = run_replay(dive, table, async_options(10.0));
  EXPECT_EQ(async->pending_counters().deferred, async->counters().not_registered);
  EXPECT_EQ(async->pending_counters().applied, 0u);
  EXPECT_GT(accepted(*sync), 50u);
  // Only the never-registered pairs waited: the links (and their order) are those of the
  // synchronous filter except that never-registered rows come when they expire.
  EXPECT_EQ(accepted(*async), accepted(*sync));
  EXPECT_EQ(async->esdf().mean(), sync->esdf().mean());
}

TEST(AsyncLinks, RegistrationAfterTheProposalLinksTheTwoDelayedStates) {
  const SyntheticDive dive = dive_with_realtime();
  const RegistrationTable table = table_of(delayed(dive));
  const auto sync = run_replay(dive, dive.registrations, async_options(0.0));
  const auto f = run_replay(dive, table, async_options(10.0));
  const PendingRegistrationCounters& p = f->pending_counters();
  EXPECT_EQ(p.applied,
            static_cast<std::uint64_t>(f->counters().links_accepted + f->counters().links_gated +
                                       f->counters().registration_failed));
  EXPECT_GT(p.accepted, 50u);
  EXPECT_EQ(p.dropped_full, 0u);
  EXPECT_TRUE(f->pending_registrations().empty());
  // Every answered pair was applied after its image, between two kept states.
  for (const LinkRecord& l : f->links()) {
    if (l.outcome == LinkOutcome::kNotRegistered) continue;
    EXPECT_GT(l.t_us, dive.image_t_us[l.frame_j]) << l.frame_i << "-" << l.frame_j;
    EXPECT_GE(l.state_j, 1);
    EXPECT_LT(l.state_i, l.state_j);
  }
  // About as many links as answering at the image (the gate uses an older, looser joint).
  EXPECT_GE(static_cast<double>(accepted(*f)), 0.9 * static_cast<double>(accepted(*sync)));
  // The map is as good: final XY error within 2x that of the synchronous filter + 2 cm.
  core::Esdf a = f->esdf(), s = sync->esdf();
  ASSERT_TRUE(a.recover_mean_direct().ok());
  ASSERT_TRUE(s.recover_mean_direct().ok());
  double worst_async = 0.0, worst_sync = 0.0;
  for (int b = 1; b < a.num_blocks(); ++b) {
    const auto& truth = dive.image_truth[f->image_of_state(b)->frame_id];
    worst_async = std::max(worst_async, (a.mean_block(b).head<2>() - truth.head<2>()).norm());
    const auto& truth_s = dive.image_truth[sync->image_of_state(b)->frame_id];
    worst_sync = std::max(worst_sync, (s.mean_block(b).head<2>() - truth_s.head<2>()).norm());
  }
  EXPECT_LE(worst_async, 2.0 * worst_sync + 0.02) << worst_async << " vs " << worst_sync;
  std::printf(
      "async: %zu accepted (%llu deferred, %llu answered), worst XY %.4f m; at the image: "
      "%zu accepted, worst XY %.4f m\n",
      accepted(*f), static_cast<unsigned long long>(p.deferred),
      static_cast<unsigned long long>(p.applied), worst_async, accepted(*sync), worst_sync);
}

TEST(AsyncLinks, LiveInsertionGivesTheLinksOfReplayForTheSameArrivalTimes) {
  const SyntheticDive dive = dive_with_realtime();
  std::vector<navlcm::registration_t> regs = delayed(dive);
  const RegistrationTable table = table_of(regs);
  const auto replay = run_replay(dive, table, async_options(3.0));
  // Live: each registration arrives (offer + drain on the filter thread) before the first
  // measurement received at or after its utime, echoing this run's id and the sequence of
  // the proposal it answers (as navd publishes them: LinkProposalPublisher), each twice (the
  // copy with another measurement: the sequence is answered, the first answer is kept), plus
  // answers for frames never taken and from another run.
  std::sort(regs.begin(), regs.end(),
            [](const auto& a, const auto& b) { return a.utime < b.utime; });
  constexpr std::int64_t kRun = 0x7e57;
  RegistrationInbox inbox(64, kRun);
  NavFilter live(async_options(3.0), &inbox.table());
  std::map<std::pair<std::int64_t, std::int64_t>, std::int64_t> sequence_of;
  navlcm::registration_t unknown = regs.front();
  unknown.frame_id_i = 1000;
  unknown.frame_id_j = 1001;
  unknown.run_id = kRun;
  ASSERT_TRUE(inbox.offer(unknown));
  std::size_t next = 0, answered = 0;
  for (const Measurement& m : dive.measurements) {
    while (next < regs.size() && regs[next].utime <= time_of(m).host_realtime_us) {
      navlcm::registration_t r = regs[next++];
      const auto it = sequence_of.find({r.frame_id_i, r.frame_id_j});
      if (it == sequence_of.end()) continue;  // never proposed: navd asked nobody for it
      r.run_id = kRun;
      r.sequence = it->second;
      navlcm::registration_t copy = r;
      copy.measurement[0] += 0.5;
      navlcm::registration_t other_run = copy;
      other_run.run_id = kRun + 1;
      ASSERT_TRUE(inbox.offer(other_run));
      ASSERT_TRUE(inbox.offer(r));
      ASSERT_TRUE(inbox.offer(copy));
      ++answered;
    }
    if (inbox.has_queued()) inbox.drain(live.pending_registrations());
    ASSERT_TRUE(live.process(m).ok());
    for (const PendingRegistration& p : live.pending_registrations()) {
      const auto key = std::make_pair(static_cast<std::int64_t>(p.frame_i),
                                      static_cast<std::int64_t>(p.frame_j));
      if (sequence_of.emplace(key, static_cast<std::int64_t>(p.sequence)).second) {
        inbox.ledger().propose(p.sequence);
      }
    }
  }
  ASSERT_TRUE(live.finish().ok());
  expect_same_links(*replay, live);
  EXPECT_GT(live.pending_counters().accepted, 20u);
  EXPECT_GT(live.pending_counters().expired, 0u);  // 3 s: some answers (up to 4.5 s) too late
  const RegistrationInboxCounters c = inbox.counters();
  EXPECT_EQ(c.wrong_run, answered);
  EXPECT_EQ(c.unknown_sequence, 1u);
  EXPECT_EQ(c.inserted, c.already_answered);  // every taken answer's copy
  EXPECT_EQ(c.inserted + c.already_answered + c.expired, 2 * answered);
  EXPECT_GT(c.expired, 0u);
  EXPECT_EQ(c.duplicates, 0u);
  EXPECT_EQ(c.dropped, 0u);
  for (const LinkRecord& l : live.links()) EXPECT_NE(l.frame_j, 1001u);
}

TEST(AsyncLinks, UnansweredPairsExpireAfterTheWait) {
  const SyntheticDive dive = dive_with_realtime();
  const RegistrationTable empty;
  const auto f = run_replay(dive, empty, async_options(5.0));
  const PendingRegistrationCounters& p = f->pending_counters();
  EXPECT_GT(p.deferred, 50u);
  EXPECT_EQ(p.expired, p.deferred);  // the last ones at finish()
  EXPECT_EQ(p.applied, 0u);
  EXPECT_EQ(f->counters().links_accepted, 0u);
  EXPECT_EQ(f->counters().not_registered, f->counters().links_proposed);
  // Expired while the data ran (not by finish() at the end): at least the wait after the image.
  const std::int64_t last_t = validity_us(dive.measurements.back());
  int expired_in_run = 0;
  for (const LinkRecord& l : f->links()) {
    if (l.t_us < last_t) {
      ++expired_in_run;
      EXPECT_GE(l.t_us, dive.image_t_us[l.frame_j] + 5'000'000);
    }
  }
  EXPECT_GT(expired_in_run, 40);
}

TEST(AsyncLinks, PendingSetIsBounded) {
  const SyntheticDive dive = dive_with_realtime();
  const RegistrationTable empty;
  NavFilter f(async_options(1000.0, 3), &empty);
  std::size_t most = 0;
  for (const Measurement& m : dive.measurements) {
    ASSERT_TRUE(f.process(m).ok());
    most = std::max(most, f.pending_registrations().size());
  }
  EXPECT_EQ(most, 3u);
  EXPECT_EQ(f.pending_counters().deferred, 3u);
  EXPECT_GT(f.pending_counters().dropped_full, 0u);
  EXPECT_EQ(f.pending_registrations().back().sequence, 3u);
  EXPECT_THROW((NavFilter{async_options(-1.0), &empty}), std::invalid_argument);
  EXPECT_THROW((NavFilter{async_options(1.0, 0), &empty}), std::invalid_argument);
}

TEST(RegistrationInbox, KeepsTheFirstAnswerCountsInvalidAndDrops) {
  RegistrationInbox inbox(4, 99);
  // The filter waits for the pair 1-2 twice (sequences 1 and 2) and for 3-3 (sequence 3).
  std::vector<PendingRegistration> waiting(3);
  for (std::uint64_t s = 1; s <= 3; ++s) {
    waiting[s - 1].sequence = s;
    waiting[s - 1].frame_i = s < 3 ? 1 : 3;
    waiting[s - 1].frame_j = s < 3 ? 2 : 3;
    waiting[s - 1].deadline_realtime_us = 1'000'000;
    inbox.ledger().propose(s);
  }
  navlcm::registration_t r{};
  r.run_id = 99;
  r.sequence = 1;
  r.frame_id_i = 1;
  r.frame_id_j = 2;
  r.success = true;
  for (int k = 0; k < 25; k += 6) r.covariance[k] = 1e-4;  // a valid 5x5 covariance
  r.measurement[0] = 0.1;
  ASSERT_TRUE(inbox.offer(r));
  r.measurement[0] = 0.2;
  r.sequence = 2;
  ASSERT_TRUE(inbox.offer(r));
  r.sequence = 3;
  r.frame_id_i = 3;
  r.frame_id_j = 3;
  ASSERT_TRUE(inbox.offer(r));
  EXPECT_EQ(inbox.drain(waiting), 3u);
  const RegistrationInboxCounters c = inbox.counters();
  EXPECT_EQ(c.inserted, 1u);
  EXPECT_EQ(c.duplicates, 1u);
  EXPECT_EQ(c.invalid, 1u);
  ASSERT_TRUE(inbox.table().find(2, 1).has_value());
  EXPECT_EQ(inbox.table().find(2, 1)->z(0), 0.1);
  EXPECT_EQ(inbox.table().generation(), 1u);
  // Bounded: without a drain a flood is dropped and counted, never blocks.
  std::uint64_t refused = 0;
  for (int k = 0; k < 10000; ++k) refused += inbox.offer(r) ? 0 : 1;
  EXPECT_GT(refused, 0u);
  EXPECT_EQ(inbox.counters().dropped, refused);
  EXPECT_EQ(inbox.counters().received + refused, 10003u);
  EXPECT_THROW((RegistrationInbox{0, 99}), std::invalid_argument);
  EXPECT_THROW((RegistrationInbox{4, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace nav::daemon
