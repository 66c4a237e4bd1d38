// RegistrationInbox: only answers to this run's own proposals that the filter still waits for
// reach the table it reads (proposal_ledger.h): another run's, an unknown sequence, one
// already answered, expired ones and one naming other frames are counted per reason; answers that
// core::registration_problem() refuses (a NaN and an indefinite covariance, frame ids out of
// order) are counted `invalid`; a valid answer beside them is inserted.
#include "nav/daemon/queue/registration_inbox.h"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

namespace nav::daemon {
namespace {

constexpr std::int64_t kRun = 0x5eed'1234'abcd'0001;
constexpr std::int64_t kDeadlineUs = 1'000'000;

core::PendingRegistration pair(std::uint64_t sequence, std::uint64_t i, std::uint64_t j,
                               std::int64_t deadline_us = kDeadlineUs) {
  core::PendingRegistration p;
  p.sequence = sequence;
  p.frame_i = i;
  p.frame_j = j;
  p.deadline_realtime_us = deadline_us;
  return p;
}

navlcm::registration_t answer(std::int64_t i, std::int64_t j, std::int64_t sequence,
                              std::int64_t run = kRun) {
  navlcm::registration_t r{};
  r.frame_id_i = i;
  r.frame_id_j = j;
  r.run_id = run;
  r.sequence = sequence;
  r.success = true;
  const double z[5] = {0.4, -0.2, 0.01, -0.02, 0.3};
  for (int k = 0; k < 5; ++k) r.measurement[k] = z[k];
  for (int k = 0; k < 25; ++k) r.covariance[k] = (k % 6 == 0) ? 1e-4 : 0.0;
  return r;
}

TEST(RegistrationInbox, InvalidAnswersAreCountedAndNeverReachTheTable) {
  RegistrationInbox inbox(8, kRun);
  // Sequence 4: a proposal with its ids the wrong way round (an answer cannot fix that).
  const std::vector<core::PendingRegistration> waiting = {pair(1, 1, 2), pair(2, 2, 3),
                                                          pair(3, 3, 4), pair(4, 4, 3)};
  for (const core::PendingRegistration& p : waiting) inbox.ledger().propose(p.sequence);
  navlcm::registration_t nan_cov = answer(1, 2, 1);
  nan_cov.covariance[12] = std::numeric_limits<double>::quiet_NaN();
  navlcm::registration_t indefinite = answer(2, 3, 2);
  indefinite.covariance[24] = -1e-4;
  EXPECT_FALSE(inbox.has_queued());
  ASSERT_TRUE(inbox.offer(nan_cov));
  EXPECT_TRUE(inbox.has_queued());
  ASSERT_TRUE(inbox.offer(indefinite));
  ASSERT_TRUE(inbox.offer(answer(4, 3, 4)));
  ASSERT_TRUE(inbox.offer(answer(3, 4, 3)));
  EXPECT_EQ(inbox.drain(waiting), 4u);
  EXPECT_FALSE(inbox.has_queued());
  const RegistrationInboxCounters c = inbox.counters();
  EXPECT_EQ(c.invalid, 3u);
  EXPECT_EQ(c.inserted, 1u);
  EXPECT_EQ(inbox.table().size(), 1u);
  EXPECT_FALSE(inbox.table().find(1, 2).has_value());
  EXPECT_FALSE(inbox.table().find(2, 3).has_value());
  EXPECT_TRUE(inbox.table().find(3, 4).has_value());
  // An invalid answer does not use its proposal up: a valid one for sequence 1 still counts.
  ASSERT_TRUE(inbox.offer(answer(1, 2, 1)));
  inbox.drain(waiting);
  EXPECT_TRUE(inbox.table().find(1, 2).has_value());
}

TEST(RegistrationInbox, OnlyAnswersToThisRunsWaitingProposalsReachTheTable) {
  RegistrationInbox inbox(16, kRun);
  for (std::uint64_t s = 1; s <= 5; ++s) inbox.ledger().propose(s);
  // The filter still waits for 1, 2, 4 and 5 (3 expired in the filter).
  std::vector<core::PendingRegistration> waiting = {pair(1, 10, 11), pair(2, 10, 12),
                                                    pair(4, 12, 13), pair(5, 13, 14)};
  ASSERT_TRUE(inbox.offer(answer(10, 11, 1, kRun + 1)));  // yesterday's run
  ASSERT_TRUE(inbox.offer(answer(10, 11, 1, 0)));         // no run id (an old answerer)
  ASSERT_TRUE(inbox.offer(answer(10, 11, 9)));            // never proposed
  ASSERT_TRUE(inbox.offer(answer(10, 11, 0)));            // sequence 0: never proposed
  ASSERT_TRUE(inbox.offer(answer(11, 12, 3)));            // the filter gave up on it
  ASSERT_TRUE(inbox.offer(answer(10, 13, 2)));  // sequence 2 is the pair 10-12
  ASSERT_TRUE(inbox.offer(answer(10, 11, 1)));  // ours
  ASSERT_TRUE(inbox.offer(answer(10, 11, 1)));  // again
  EXPECT_EQ(inbox.drain(waiting), 8u);
  const RegistrationInboxCounters c = inbox.counters();
  EXPECT_EQ(c.wrong_run, 2u);
  EXPECT_EQ(c.unknown_sequence, 2u);
  EXPECT_EQ(c.expired, 1u);
  EXPECT_EQ(c.pair_mismatch, 1u);
  EXPECT_EQ(c.already_answered, 1u);
  EXPECT_EQ(c.inserted, 1u);
  EXPECT_EQ(c.invalid, 0u);
  EXPECT_EQ(inbox.table().size(), 1u);
  EXPECT_TRUE(inbox.table().find(10, 11).has_value());
  EXPECT_FALSE(inbox.table().find(10, 13).has_value());
  // Sequence 2 was not used up by the mismatching answer; once the filter stops waiting for 4
  // its answer is expired.
  waiting.erase(waiting.begin());  // 1 resolved by the filter
  ASSERT_TRUE(inbox.offer(answer(10, 12, 2)));
  inbox.drain(waiting);
  EXPECT_TRUE(inbox.table().find(10, 12).has_value());
  waiting = {pair(5, 13, 14)};
  ASSERT_TRUE(inbox.offer(answer(12, 13, 4)));
  inbox.drain(waiting);
  EXPECT_EQ(inbox.counters().expired, 2u);
  EXPECT_FALSE(inbox.table().find(12, 13).has_value());
  EXPECT_EQ(inbox.counters().inserted, 2u);
}

TEST(ProposalLedger, RunIdsAreNonZeroAndDiffer) {
  const std::int64_t a = draw_run_id(), b = draw_run_id();
  EXPECT_NE(a, 0);
  EXPECT_NE(b, 0);
  EXPECT_NE(a, b);  // 2^-64 chance of a false failure
  EXPECT_THROW(ProposalLedger(0), std::invalid_argument);
  ProposalLedger ledger(a);
  ledger.propose(3);
  EXPECT_THROW(ledger.propose(3), std::invalid_argument);  // sequences increase
}

}  // namespace
}  // namespace nav::daemon
