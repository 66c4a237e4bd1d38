// core::NavFilter configured by plain options (no config file, no daemon): a vehicle moving
// straight north at 0.5 m/s at 100 m depth with noise-free DVL, attitude and depth messages and
// an image every 2 s. The filter initialises at the first held message, tracks the motion,
// keeps one delayed state per image and proposes links between overlapping images (none
// registered); a filter restored from its serialised state (archive.h) and the map classes
// continues bit-identically, as does a copy taken with a recovery job in flight; invalid
// options are refused naming the option.
#include <gtest/gtest.h>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "nav/core/navigation/nav_filter.h"
#include "nav/core/navigation/nav_filter_serialization.h"
#include "nav/core/serialization/archive.h"
#include "nav/testing/straight_line.h"

namespace nav::core {
namespace {

using Bytes = std::vector<std::uint8_t>;
using testing::kDepthM;
using testing::kSpeedMps;
using testing::straight_line;
using testing::straight_line_options;

Bytes state_of(const NavFilter& f) { return to_bytes(f); }

TEST(NavFilterCore, InitialisesTracksTheRunAndKeepsOneStatePerImage) {
  const std::vector<Measurement> ms = straight_line(60.0);
  NavFilter f(straight_line_options(), nullptr);
  for (const Measurement& m : ms) ASSERT_TRUE(f.process(m).ok());
  ASSERT_TRUE(f.finish().ok());
  ASSERT_TRUE(f.initialised());
  const Vec12 robot = f.esdf().mean_block(Esdf::kRobotBlock);
  const double t_s = 1e-6 * static_cast<double>(f.time_us());
  EXPECT_NEAR(robot(0), kSpeedMps * t_s, 0.05) << "north after " << t_s << " s";
  EXPECT_NEAR(robot(1), 0.0, 1e-3);
  EXPECT_NEAR(robot(2), kDepthM, 1e-3) << "depth of the reference point";
  EXPECT_NEAR(robot(6), kSpeedMps, 1e-3) << "surge";
  EXPECT_EQ(f.counters().images, 30u);
  EXPECT_EQ(f.images().size(), 30u);
  EXPECT_EQ(f.esdf().num_blocks(), 31);  // robot + one delayed state per image
  for (const ImageRecord& im : f.images()) EXPECT_GE(im.state, 1);
  // Images 1 m apart with ~2 m footprints: pairs are proposed; no table, so none registered.
  EXPECT_GT(f.counters().links_proposed, 0u);
  EXPECT_EQ(f.counters().not_registered, f.counters().links_proposed);
  EXPECT_EQ(f.counters().update_failures, 0u);
  EXPECT_EQ(f.counters().recovery_failures, 0u);
  EXPECT_EQ(f.innovations().sensors().size(), 3u);  // DVL, attitude, depth
}

TEST(NavFilterCore, BeforeProposalSeesEachImageAfterItsRecoveryAndBeforeItsProposals) {
  const std::vector<Measurement> ms = straight_line(20.0);
  NavFilter f(straight_line_options(), nullptr);
  std::vector<std::uint64_t> seen;
  f.set_before_proposal([&seen](const NavFilter& at) {
    seen.push_back(at.images().back().frame_id);
    // This image's proposals are not recorded yet; every earlier image's are.
    EXPECT_EQ(at.proposals().size() + 1, at.images().size());
    // The robot is the image: its delayed states are the earlier images.
    EXPECT_EQ(static_cast<std::size_t>(at.esdf().num_blocks()), at.images().size());
  });
  for (const Measurement& m : ms) ASSERT_TRUE(f.process(m).ok());
  ASSERT_EQ(seen.size(), f.images().size());
  for (std::size_t k = 0; k < seen.size(); ++k) EXPECT_EQ(seen[k], f.images()[k].frame_id);
  // Cleared, it is no longer called.
  f.set_before_proposal({});
  for (const Measurement& m : straight_line(24.0)) {
    if (validity_us(m) <= 20'000'000) continue;
    ASSERT_TRUE(f.process(m).ok());
  }
  EXPECT_GT(f.images().size(), seen.size());
}

TEST(NavFilterCore, RestoredFromItsSerialisedStateContinuesBitIdentically) {
  const std::vector<Measurement> ms = straight_line(40.0);
  const NavFilterOptions options = straight_line_options();
  for (std::size_t cut : {std::size_t{3}, ms.size() / 3, ms.size() / 2 + 1}) {
    NavFilter original(options, nullptr);
    for (std::size_t i = 0; i < cut; ++i) ASSERT_TRUE(original.process(ms[i]).ok());
    const Bytes saved = state_of(original);
    NavFilter restored(options, nullptr);
    restored.restore_map(original.esdf(), original.bounds(), original.recovery());
    ReadArchive ar(saved, "NAVF");
    restored.serialize(ar);
    ASSERT_TRUE(ar.finish().ok()) << ar.finish().message();
    EXPECT_EQ(state_of(restored), saved) << "cut " << cut;
    for (std::size_t i = cut; i < ms.size(); ++i) {
      ASSERT_TRUE(original.process(ms[i]).ok());
      ASSERT_TRUE(restored.process(ms[i]).ok());
    }
    ASSERT_TRUE(original.finish().ok());
    ASSERT_TRUE(restored.finish().ok());
    EXPECT_EQ(state_of(restored), state_of(original)) << "cut " << cut;
    EXPECT_TRUE(restored.esdf().mean() == original.esdf().mean()) << "cut " << cut;
  }
}

TEST(NavFilterCore, ReadingRefusesIndicesTheFilterDoesNotHave) {
  const std::vector<Measurement> ms = straight_line(20.0);
  NavFilter original(straight_line_options(), nullptr);
  for (const Measurement& m : ms) ASSERT_TRUE(original.process(m).ok());
  const Bytes saved = state_of(original);
  // The map sections are not restored: a fresh filter has one block, the state names ten.
  NavFilter fresh(straight_line_options(), nullptr);
  ReadArchive ar(saved, "NAVF");
  fresh.serialize(ar);
  const Status s = ar.finish();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("NAVF"), std::string::npos) << s.message();
}

TEST(NavFilterCore, InlineRecoveryJobsSurviveACopyInFlight) {
  NavFilterOptions options = straight_line_options();
  options.recovery_thread = true;  // no executor given: InlineRecoveryExecutor
  options.recovery_handoff_s = 10.0;
  const std::vector<Measurement> ms = straight_line(30.0);
  NavFilter a(options, nullptr);
  std::size_t i = 0;
  for (; i < ms.size() && !a.recovery_in_flight(); ++i) ASSERT_TRUE(a.process(ms[i]).ok());
  ASSERT_TRUE(a.recovery_in_flight());
  NavFilter b(a);
  EXPECT_TRUE(b.recovery_in_flight());
  for (; i < ms.size(); ++i) {
    ASSERT_TRUE(a.process(ms[i]).ok());
    ASSERT_TRUE(b.process(ms[i]).ok());
  }
  ASSERT_TRUE(a.finish().ok());
  ASSERT_TRUE(b.finish().ok());
  EXPECT_EQ(state_of(a), state_of(b));
  EXPECT_GT(a.counters().recoveries, 0u);
}

TEST(NavFilterCore, InvalidOptionsAreRefusedNamingTheOption) {
  NavFilterOptions o = straight_line_options();
  o.recovery_handoff_s = -1.0;
  try {
    NavFilter f(o, nullptr);
    FAIL() << "accepted a negative hand-off";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("recovery_handoff_s"), std::string::npos) << e.what();
  }
  o = straight_line_options();
  o.max_pending_registrations = 0;
  o.registration_wait_s = 1.0;
  try {
    NavFilter f(o, nullptr);
    FAIL() << "accepted max_pending_registrations 0";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_pending_registrations"), std::string::npos);
  }
  o = straight_line_options();
  o.sensors[3].camera->fx_px = 0.0;
  EXPECT_THROW(NavFilter(o, nullptr), std::invalid_argument);
}

}  // namespace
}  // namespace nav::core
