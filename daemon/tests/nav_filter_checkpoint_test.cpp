// NavFilter checkpoints (filter/nav_filter_checkpoint.h) on the synthetic dive of
// support/synthetic_dive.h: a filter restored from a checkpoint taken anywhere in the dive
// (before initialisation, between images with the recovery's warm start behind the filter,
// with a pending image) and fed the remaining
// measurements ends bit-identical to the uninterrupted filter, link history and trajectory
// included; every 11th truncation of the NAVF section is refused, a flipped byte (every 17th) is
// refused or decodes to exactly those bytes, and a refused restore leaves the filter untouched.
#include "nav/daemon/checkpoint/nav_filter_checkpoint.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <vector>

#include "nav/core/navigation/nav_filter.h"
#include "nav/core/serialization/sections.h"
#include "nav/daemon/checkpoint/nav_filter_checkpointer.h"
#include "nav/daemon/checkpoint/resume_point.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "support/nav_filter_fixture.h"

namespace nav::daemon {
namespace {

using nav::testing::Bytes;
using nav::testing::encode;
using Fixture = nav::testing::NavFilterFixture;

core::Status restore(const Bytes& payload, NavFilter* f, bool verify_crc = true) {
  core::SectionSet set;
  if (core::Status s = core::SectionSet::decode(payload, &set, {verify_crc}); !s.ok()) return s;
  return restore_nav_filter(set, f);
}

TEST(NavFilterCheckpoint, ResumedFilterEndsBitIdentical) {
  const Fixture fx(120.0);
  const auto& ms = fx.dive.measurements;
  auto reference = fx.make();
  for (const Measurement& m : ms) ASSERT_TRUE(reference->process(m).ok());
  ASSERT_TRUE(reference->finish().ok());
  const Bytes expected = encode(*reference);
  ASSERT_GT(reference->counters().links_accepted, 20u);

  // Cut points: before initialisation, just after, right after an image (pending), mid-dive,
  // near the end.
  std::vector<std::size_t> cuts = {0, 1, 5, ms.size() / 2, ms.size() - 3};
  for (std::size_t k = 1; k < 8; ++k) cuts.push_back(k * ms.size() / 8 + 3);  // between images
  for (std::size_t i = 10; i < ms.size(); ++i) {
    if (std::holds_alternative<ImageEvent>(ms[i]) && i > ms.size() / 3) {
      cuts.push_back(i + 1);
      break;
    }
  }
  for (std::size_t cut : cuts) {
    auto original = fx.make();
    for (std::size_t i = 0; i < cut; ++i) ASSERT_TRUE(original->process(ms[i]).ok());
    const Bytes checkpoint = encode(*original);
    auto resumed = fx.make();
    const core::Status s = restore(checkpoint, resumed.get());
    ASSERT_TRUE(s.ok()) << "cut " << cut << ": " << s.to_string();
    EXPECT_EQ(encode(*resumed), checkpoint) << "cut " << cut;
    for (std::size_t i = cut; i < ms.size(); ++i) ASSERT_TRUE(resumed->process(ms[i]).ok());
    ASSERT_TRUE(resumed->finish().ok());
    EXPECT_EQ(encode(*resumed), expected) << "cut " << cut;
    EXPECT_EQ(resumed->links().size(), reference->links().size());
    EXPECT_EQ(resumed->esdf().num_blocks(), reference->esdf().num_blocks());  // no state lost
  }
}

// config/sim.yaml's kept factor is not checkpointed: the restored filter factors its Λ afresh
// at the next image (docs/formats.md "Checkpoints"). The run then equals the uninterrupted one
// up to rounding: the same states and links, means and bounds within 1e-9 of their scale.
TEST(NavFilterCheckpoint, ResumedWithTheKeptFactorEqualsTheRunUpToRounding) {
  const Fixture fx(120.0);
  NavdConfig config = fx.config;
  config.filter.recovery_preconditioner = core::RecoveryPreconditioner::kFactor;
  config.filter.recovery_keep_factor_equal = true;
  config.filter.recovery_refresh_interval = 10;
  const NavFilterOptions options = filter_options_from_config(config);
  const auto& ms = fx.dive.measurements;
  auto reference = fx.make(options);
  for (const Measurement& m : ms) ASSERT_TRUE(reference->process(m).ok());
  ASSERT_TRUE(reference->finish().ok());
  ASSERT_GT(reference->counters().links_accepted, 20u);
  for (const std::size_t cut : {ms.size() / 3, 2 * ms.size() / 3}) {
    auto original = fx.make(options);
    for (std::size_t i = 0; i < cut; ++i) ASSERT_TRUE(original->process(ms[i]).ok());
    auto resumed = fx.make(options);
    ASSERT_TRUE(restore(encode(*original), resumed.get()).ok()) << "cut " << cut;
    for (std::size_t i = cut; i < ms.size(); ++i) ASSERT_TRUE(resumed->process(ms[i]).ok());
    ASSERT_TRUE(resumed->finish().ok());
    ASSERT_EQ(resumed->esdf().num_blocks(), reference->esdf().num_blocks());
    EXPECT_EQ(resumed->links().size(), reference->links().size());
    const Eigen::VectorXd& mean = reference->esdf().mean();
    const double mean_diff = (resumed->esdf().mean() - mean).lpNorm<Eigen::Infinity>();
    double bound_diff = 0.0;  // relative to the bound's own size
    for (int i = 1; i < reference->esdf().num_blocks(); ++i) {
      const Eigen::MatrixXd& b = reference->bounds().bound(i);
      bound_diff = std::max(bound_diff, (resumed->bounds().bound(i) - b).norm() / b.norm());
    }
    std::printf("cut %zu: max mean difference %.3g (mean scale %.3g), max bound difference %.3g\n",
                cut, mean_diff, mean.lpNorm<Eigen::Infinity>(), bound_diff);
    EXPECT_LT(mean_diff, 1e-9 * mean.lpNorm<Eigen::Infinity>()) << "cut " << cut;
    EXPECT_LT(bound_diff, 1e-9) << "cut " << cut;
  }
}

TEST(NavFilterCheckpoint, CorruptNavfIsRefusedAndTheFilterUntouched) {
  const Fixture fx(12.0);  // a few images: small sections, every byte tried quickly
  auto f = fx.make();
  for (const Measurement& m : fx.dive.measurements) ASSERT_TRUE(f->process(m).ok());
  ASSERT_GE(f->images().size(), 4u);
  const Bytes payload = encode(*f);
  core::SectionSet set;
  ASSERT_TRUE(core::SectionSet::decode(payload, &set).ok());
  const core::SectionView* navf = set.find(kNavFilterSectionTag);
  ASSERT_NE(navf, nullptr);
  const Bytes navf_bytes(navf->bytes.begin(), navf->bytes.end());
  // The map sections as they are, NAVF replaced by `bytes`.
  auto with_navf = [&](const Bytes& bytes) {
    core::SectionWriter w;
    for (const core::SectionView& v : set.sections()) {
      EXPECT_TRUE(
          w.add(v.tag, v.version,
                v.tag == kNavFilterSectionTag ? bytes : Bytes(v.bytes.begin(), v.bytes.end()))
              .ok());
    }
    return w.finish();
  };
  auto target = fx.make();
  const Bytes untouched = encode(*target);
  for (std::size_t len = 0; len < navf_bytes.size(); len += 11) {
    const Bytes cut(navf_bytes.begin(), navf_bytes.begin() + static_cast<std::ptrdiff_t>(len));
    ASSERT_FALSE(restore(with_navf(cut), target.get()).ok()) << "NAVF truncated to " << len;
  }
  EXPECT_EQ(encode(*target), untouched);
  int accepted = 0;
  for (std::size_t i = 0; i < navf_bytes.size(); i += 17) {
    Bytes bad = navf_bytes;
    bad[i] ^= 0xFF;
    auto g = fx.make();
    if (restore(with_navf(bad), g.get(), false).ok()) {
      ++accepted;
      core::SectionSet again;
      const Bytes re = encode(*g);
      ASSERT_TRUE(core::SectionSet::decode(re, &again).ok());
      const core::SectionView* v = again.find(kNavFilterSectionTag);
      ASSERT_EQ(Bytes(v->bytes.begin(), v->bytes.end()), bad) << "byte " << i;
    }
  }
  EXPECT_GT(accepted, 0);
  // With the CRC on, the same flip is refused outright, naming the section.
  Bytes flipped = payload;
  flipped[static_cast<std::size_t>(navf->offset) + 10] ^= 0x01;
  const core::Status s = restore(flipped, target.get());
  EXPECT_NE(s.message().find("CRC-32 mismatch in section NAVF"), std::string::npos) << s.message();
  EXPECT_EQ(encode(*target), untouched);
}

TEST(NavFilterCheckpointer, StopResumeAndSkipEndBitIdentical) {
  const Fixture fx(60.0);
  const auto& ms = fx.dive.measurements;
  auto reference = fx.make();
  for (const Measurement& m : ms) ASSERT_TRUE(reference->process(m).ok());
  ASSERT_TRUE(reference->finish().ok());

  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("nav_filter_checkpointer_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  CheckpointConfig config;
  config.path = dir.string();
  config.period_s = 1e-3;
  config.keep = 2;
  {  // First run: stopped (SIGTERM) half-way, shutdown checkpoint written.
    auto f = fx.make();
    NavFilterCheckpointer checkpointer(config);
    for (std::size_t i = 0; i < ms.size() / 2; ++i) {
      ASSERT_TRUE(f->process(ms[i]).ok());
      checkpointer.after_measurement(*f, ms[i]);
    }
    checkpointer.shutdown(*f);
    const CheckpointWorkerStats s = checkpointer.stats();
    EXPECT_GE(s.written, 1u);
    EXPECT_EQ(s.failed, 0u);
    EXPECT_EQ(checkpointer.point().applied, ms.size() / 2);
  }
  ResumedNavFilter resumed = resume_nav_filter(dir, [&fx] { return fx.make(); });
  ASSERT_NE(resumed.filter, nullptr);
  EXPECT_TRUE(resumed.skipped.empty());
  EXPECT_EQ(resumed.point.applied, ms.size() / 2);
  {  // Second run: the whole input again, what the checkpoint holds skipped.
    NavFilterCheckpointer checkpointer(config, resumed.point);
    ResumeSkipper skipper(resumed.point);
    for (const Measurement& m : ms) {
      if (skipper.skip(m)) continue;
      ASSERT_TRUE(resumed.filter->process(m).ok());
      checkpointer.after_measurement(*resumed.filter, m);
    }
    EXPECT_EQ(skipper.skipped(), ms.size() / 2);
    checkpointer.shutdown(*resumed.filter);
    EXPECT_EQ(checkpointer.point().applied, ms.size());
  }
  ASSERT_TRUE(resumed.filter->finish().ok());
  EXPECT_EQ(encode(*resumed.filter), encode(*reference));
  // A checkpoint written by another payload version is skipped with the reason.
  CheckpointWriter writer(dir, 2);
  ASSERT_TRUE(writer.write(kNavFilterPayloadVersion + 1, Bytes{1, 2, 3}).ok);
  resumed = resume_nav_filter(dir, [&fx] { return fx.make(); });
  ASSERT_EQ(resumed.skipped.size(), 1u);
  const std::string expected = "payload version " + std::to_string(kNavFilterPayloadVersion + 1) +
                               ", this navd reads " + std::to_string(kNavFilterPayloadVersion);
  EXPECT_NE(resumed.skipped[0].reason.find(expected), std::string::npos)
      << resumed.skipped[0].reason;
  EXPECT_EQ(resumed.point.applied, ms.size());
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace nav::daemon
