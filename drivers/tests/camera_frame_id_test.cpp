// FrameIdUnwrapper: GigE Vision 1.x 16-bit block ids (0 skipped on wrap-around), 32-bit V4L2
// sequences (0 used), 64-bit extended ids; gaps, duplicates and counter restarts.

#include <gtest/gtest.h>

#include "nav/drivers/transports/camera.h"

namespace nav::drivers {
namespace {

TEST(CameraFrameId, SixteenBitBlockIdWrapsFrom65535To1WithoutLoss) {
  FrameIdUnwrapper ids(16, true);
  EXPECT_EQ(ids.update(65534).id, 65534u);
  const auto a = ids.update(65535);
  const auto b = ids.update(1);  // 0 is reserved: 65535 -> 1 is consecutive
  const auto c = ids.update(2);
  EXPECT_EQ(a.id, 65535u);
  EXPECT_EQ(b.id, 65536u);
  EXPECT_EQ(c.id, 65537u);
  EXPECT_EQ(a.lost + b.lost + c.lost, 0u);
  EXPECT_FALSE(b.restarted);
}

TEST(CameraFrameId, GapsAcrossTheWrapCountLostFrames) {
  FrameIdUnwrapper ids(16, true);
  ids.update(65533);
  const auto u = ids.update(3);  // missing: 65534, 65535, 1, 2
  EXPECT_EQ(u.lost, 4u);
  EXPECT_EQ(u.id, 65533u + 5u);
}

TEST(CameraFrameId, ThirtyTwoBitSequenceUsesZero) {
  FrameIdUnwrapper ids(32, false);
  ids.update(0xFFFFFFFEu);
  ids.update(0xFFFFFFFFu);
  const auto u = ids.update(0);
  EXPECT_EQ(u.lost, 0u);
  EXPECT_EQ(u.id, 0x100000000u);
}

TEST(CameraFrameId, SixtyFourBitIdsAndDuplicates) {
  FrameIdUnwrapper ids(64, false);
  EXPECT_EQ(ids.update(1000).id, 1000u);
  const auto d = ids.update(1000);
  EXPECT_TRUE(d.duplicate);
  EXPECT_EQ(d.id, 1000u);
  const auto g = ids.update(1010);
  EXPECT_EQ(g.lost, 9u);
  EXPECT_EQ(g.id, 1010u);
}

TEST(CameraFrameId, BackwardsJumpIsARestartNotAHugeLoss) {
  FrameIdUnwrapper ids(16, true);
  ids.update(40000);
  // 1000 ids backwards (forward distance 64535 > half the period): the counter was reset,
  // e.g. by a GevTimestampControlReset or a camera power cycle.
  const auto u = ids.update(39000);
  EXPECT_TRUE(u.restarted);
  EXPECT_EQ(u.lost, 0u);
  EXPECT_EQ(u.id, 40001u);  // unwrapped ids stay strictly increasing
  EXPECT_EQ(ids.update(39001).id, 40002u);
}

TEST(CameraFrameId, ResetStartsFromTheNextRawId) {
  FrameIdUnwrapper ids(16, true);
  ids.update(100);
  ids.reset();
  const auto u = ids.update(7);
  EXPECT_EQ(u.id, 7u);
  EXPECT_FALSE(u.restarted);
}

}  // namespace
}  // namespace nav::drivers
