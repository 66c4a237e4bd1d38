// RegistrationInbox: answers received over LCM that core::registration_problem() refuses (here a
// NaN and an indefinite covariance, and frame ids out of order) are counted `invalid` and never
// reach the table the filter reads; a valid answer beside them is inserted.
#include "nav/daemon/queue/registration_inbox.h"

#include <gtest/gtest.h>

#include <limits>

namespace nav::daemon {
namespace {

navlcm::registration_t answer(std::int64_t i, std::int64_t j) {
  navlcm::registration_t r{};
  r.frame_id_i = i;
  r.frame_id_j = j;
  r.success = true;
  const double z[5] = {0.4, -0.2, 0.01, -0.02, 0.3};
  for (int k = 0; k < 5; ++k) r.measurement[k] = z[k];
  for (int k = 0; k < 25; ++k) r.covariance[k] = (k % 6 == 0) ? 1e-4 : 0.0;
  return r;
}

TEST(RegistrationInbox, InvalidAnswersAreCountedAndNeverReachTheTable) {
  RegistrationInbox inbox(8);
  navlcm::registration_t nan_cov = answer(1, 2);
  nan_cov.covariance[12] = std::numeric_limits<double>::quiet_NaN();
  navlcm::registration_t indefinite = answer(2, 3);
  indefinite.covariance[24] = -1e-4;
  ASSERT_TRUE(inbox.offer(nan_cov));
  ASSERT_TRUE(inbox.offer(indefinite));
  ASSERT_TRUE(inbox.offer(answer(5, 4)));  // ids out of order
  ASSERT_TRUE(inbox.offer(answer(3, 4)));
  EXPECT_EQ(inbox.drain(), 4u);
  const RegistrationInboxCounters c = inbox.counters();
  EXPECT_EQ(c.invalid, 3u);
  EXPECT_EQ(c.inserted, 1u);
  EXPECT_EQ(inbox.table().size(), 1u);
  EXPECT_FALSE(inbox.table().find(1, 2).has_value());
  EXPECT_FALSE(inbox.table().find(2, 3).has_value());
  EXPECT_TRUE(inbox.table().find(3, 4).has_value());
}

}  // namespace
}  // namespace nav::daemon
