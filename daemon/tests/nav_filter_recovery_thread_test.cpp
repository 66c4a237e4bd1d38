// NavFilter's recovery thread (recovery_executor.h, recovery_worker.h) on the
// synthetic dive of support/synthetic_dive.h: the outputs (the whole checkpointed state, link
// history and trajectory) are bit-identical across runs, with random delays injected on the
// recovery thread, and to the jobs run inline on the filter thread; a checkpoint or a copy
// taken with a job in flight continues bit-identically; a filter destroyed with a slow job in
// flight shuts down cleanly; the threaded filter agrees with the synchronous one to a stated
// tolerance and its bounds stay certified against exact marginals.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/serialization/sections.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/filter/recovery_worker.h"
#include "nav/daemon/checkpoint/nav_filter_checkpoint.h"
#include "nav/core/navigation/nav_filter.h"
#include "support/nav_filter_fixture.h"

namespace nav::daemon {
namespace {

using nav::testing::Bytes;
using nav::testing::encode;

/// The synthetic dive with the recovery thread on (opt-in: filter.recovery_thread).
struct Fixture : nav::testing::NavFilterFixture {
  explicit Fixture(double duration_s) : NavFilterFixture(duration_s) {
    options.recovery_thread = true;
    options.recovery_executor = threaded_recovery_executor();
  }
};

Bytes run_all(const Fixture& fx, const NavFilterOptions& o) {
  auto f = fx.make(o);
  for (const Measurement& m : fx.dive.measurements) EXPECT_TRUE(f->process(m).ok());
  EXPECT_TRUE(f->finish().ok());
  EXPECT_EQ(f->counters().recovery_failures, 0u);
  return encode(*f);
}

/// A hook sleeping 0-3 ms at random (its own generator, seeded per run) before each job.
std::function<void()> random_delays(unsigned seed) {
  auto state = std::make_shared<std::pair<std::mutex, std::mt19937>>();
  state->second.seed(seed);
  return [state] {
    int us = 0;
    {
      const std::lock_guard<std::mutex> lock(state->first);
      us = std::uniform_int_distribution<int>(0, 3000)(state->second);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(us));
  };
}

/// Index just past the first measurement after the first image past `fraction` of the dive at
/// which a job is in flight (the prediction that keeps the image's state submits it), found by
/// a probe filter with options `o` (the schedule is a function of the data).
std::size_t after_image(const Fixture& fx, const NavFilterOptions& o, double fraction) {
  const auto& ms = fx.dive.measurements;
  auto probe = fx.make(o);
  const auto start = static_cast<std::size_t>(fraction * static_cast<double>(ms.size()));
  bool image = false;
  for (std::size_t i = 0; i < ms.size(); ++i) {
    EXPECT_TRUE(probe->process(ms[i]).ok());
    if (i >= start && std::holds_alternative<ImageEvent>(ms[i])) {
      image = true;
    } else if (image && probe->recovery_in_flight()) {
      return i + 1;
    }
  }
  return ms.size();
}

TEST(RecoveryThread, OutputsBitIdenticalAcrossRunsDelaysAndInline) {
  const Fixture fx(60.0);
  NavFilterOptions o = fx.options;
  // Hand-off 0.5 s after each image (images every 2 s): taken at a measurement in process().
  NavFilterOptions early = o;
  early.recovery_handoff_s = 0.5;
  const Bytes early_bytes = run_all(fx, early);
  early.recovery_executor = threaded_recovery_executor(random_delays(3));
  EXPECT_EQ(run_all(fx, early), early_bytes) << "hand-off 0.5 s, random delays";
  early.recovery_executor = {};  // core::InlineRecoveryExecutor
  EXPECT_EQ(run_all(fx, early), early_bytes) << "hand-off 0.5 s, inline";
  // Default hand-off (10 s): the next image takes each job.
  const Bytes first = run_all(fx, o);
  EXPECT_NE(first, early_bytes) << "the hand-off time is a data-time schedule of its own";
  EXPECT_EQ(run_all(fx, o), first) << "second run";
  for (unsigned seed : {1u, 2u}) {
    NavFilterOptions delayed = o;
    delayed.recovery_executor = threaded_recovery_executor(random_delays(seed));
    EXPECT_EQ(run_all(fx, delayed), first) << "random delays, seed " << seed;
  }
  NavFilterOptions inline_jobs = o;
  inline_jobs.recovery_executor = {};  // core::InlineRecoveryExecutor
  EXPECT_EQ(run_all(fx, inline_jobs), first) << "jobs inline on the filter thread";
  NavFilterOptions sync = o;
  sync.recovery_thread = false;
  EXPECT_NE(run_all(fx, sync), first) << "the synchronous path is a different schedule";
}

TEST(RecoveryThread, CheckpointAndCopyWithAJobInFlightContinueBitIdentical) {
  const Fixture fx(60.0);
  const auto& ms = fx.dive.measurements;
  NavFilterOptions o = fx.options;
  const Bytes expected = run_all(fx, o);
  o.recovery_executor = threaded_recovery_executor(
      [] { std::this_thread::sleep_for(std::chrono::milliseconds(20)); });
  for (double fraction : {0.3, 0.7}) {
    const std::size_t cut = after_image(fx, o, fraction);
    auto original = fx.make(o);
    for (std::size_t i = 0; i < cut; ++i) ASSERT_TRUE(original->process(ms[i]).ok());
    ASSERT_TRUE(original->recovery_in_flight()) << "cut " << cut;
    NavFilter copy(*original);  // waits for the job, the copy gets its result
    EXPECT_TRUE(copy.recovery_in_flight());
    core::SectionSet set;
    const Bytes checkpoint = encode(*original);  // waits for the job, stores its result
    ASSERT_TRUE(core::SectionSet::decode(checkpoint, &set).ok());
    auto resumed = fx.make(o);
    ASSERT_TRUE(restore_nav_filter(set, resumed.get()).ok());
    EXPECT_TRUE(resumed->recovery_in_flight());
    EXPECT_EQ(encode(*resumed), checkpoint);
    for (NavFilter* f : {original.get(), &copy, resumed.get()}) {
      for (std::size_t i = cut; i < ms.size(); ++i) ASSERT_TRUE(f->process(ms[i]).ok());
      ASSERT_TRUE(f->finish().ok());
      EXPECT_FALSE(f->recovery_in_flight());
      EXPECT_EQ(encode(*f), expected) << "cut " << cut;
    }
  }
}

TEST(RecoveryThread, ResumedWithoutTheThreadDropsTheJob) {
  const Fixture fx(30.0);
  const auto& ms = fx.dive.measurements;
  auto original = fx.make(fx.options);
  const std::size_t cut = after_image(fx, fx.options, 0.5);
  for (std::size_t i = 0; i < cut; ++i) ASSERT_TRUE(original->process(ms[i]).ok());
  ASSERT_TRUE(original->recovery_in_flight());
  core::SectionSet set;
  const Bytes checkpoint = encode(*original);
  ASSERT_TRUE(core::SectionSet::decode(checkpoint, &set).ok());
  NavFilterOptions sync = fx.options;
  sync.recovery_thread = false;
  auto resumed = fx.make(sync);
  ASSERT_TRUE(restore_nav_filter(set, resumed.get()).ok());
  EXPECT_FALSE(resumed->recovery_in_flight());
  for (std::size_t i = cut; i < ms.size(); ++i) ASSERT_TRUE(resumed->process(ms[i]).ok());
  ASSERT_TRUE(resumed->finish().ok());
  EXPECT_EQ(resumed->counters().recovery_failures, 0u);
}

TEST(RecoveryThread, DestroyedWithASlowJobInFlightShutsDownCleanly) {
  const Fixture fx(20.0);
  const auto& ms = fx.dive.measurements;
  NavFilterOptions o = fx.options;
  auto started = std::make_shared<std::atomic<int>>(0);
  o.recovery_executor = threaded_recovery_executor([started] {
    ++*started;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  });
  auto f = fx.make(o);
  const std::size_t cut = after_image(fx, o, 0.5);
  for (std::size_t i = 0; i < cut; ++i) ASSERT_TRUE(f->process(ms[i]).ok());
  ASSERT_TRUE(f->recovery_in_flight());
  f.reset();  // lets the job in flight finish (it cannot be interrupted), then joins
  EXPECT_GE(started->load(), 1);
  // A filter that never started a job stops at once, too.
  auto idle = fx.make(o);
  EXPECT_FALSE(idle->recovery_in_flight());
  idle.reset();
}

TEST(RecoveryThread, AgreesWithSynchronousRecoveryAndStaysCertified) {
  const Fixture fx(160.0);
  NavFilterOptions threaded = fx.options;
  NavFilterOptions sync = fx.options;
  sync.recovery_thread = false;
  auto a = fx.make(threaded);
  auto b = fx.make(sync);
  for (const Measurement& m : fx.dive.measurements) {
    ASSERT_TRUE(a->process(m).ok());
    ASSERT_TRUE(b->process(m).ok());
  }
  ASSERT_TRUE(a->finish().ok());
  ASSERT_TRUE(b->finish().ok());
  ASSERT_EQ(a->images().size(), b->images().size());
  // Stated tolerance: the robot means at the images differ by less than 5 cm (measured 2.1 cm,
  // 1.4 sigma of the recovered Σ_rr: the filters differ by one image of lag in the PCG
  // refinement, hence in the delayed states' linearisation points; both are 6.7-6.8 cm RMS
  // from the truth here), the xy RMS errors against the truth agree within 1 cm, accepted links
  // within 15 % (measured 298 vs 268: the per-image proposal cap ranks pairs by overlap
  // probability, so one image of lag in the bounds picks some different pairs).
  double max_xy = 0.0, max_ratio = 0.0, sq_a = 0.0, sq_b = 0.0;
  for (std::size_t i = 0; i < a->images().size(); ++i) {
    const ImageRecord& ia = a->images()[i];
    const ImageRecord& ib = b->images()[i];
    const double d = (ia.robot_mean.head<2>() - ib.robot_mean.head<2>()).norm();
    const double sigma =
        std::sqrt(core::lambda_max_symmetric(ib.robot_covariance.topLeftCorner(2, 2)));
    max_xy = std::max(max_xy, d);
    max_ratio = std::max(max_ratio, d / sigma);
    const core::Vec12& truth = fx.dive.image_truth.at(ia.frame_id);
    sq_a += (ia.robot_mean.head<2>() - truth.head<2>()).squaredNorm();
    sq_b += (ib.robot_mean.head<2>() - truth.head<2>()).squaredNorm();
  }
  const double n = static_cast<double>(a->images().size());
  const double rms_a = std::sqrt(sq_a / n), rms_b = std::sqrt(sq_b / n);
  std::printf(
      "threaded vs synchronous: max robot xy difference %.4f m (%.3f sigma), xy RMS error "
      "%.4f vs %.4f m, links %llu vs %llu\n",
      max_xy, max_ratio, rms_a, rms_b,
      static_cast<unsigned long long>(a->counters().links_accepted),
      static_cast<unsigned long long>(b->counters().links_accepted));
  EXPECT_LT(max_xy, 0.05);
  EXPECT_NEAR(rms_a, rms_b, 0.01);
  const auto la = static_cast<double>(a->counters().links_accepted);
  const auto lb = static_cast<double>(b->counters().links_accepted);
  EXPECT_GT(lb, 100.0);
  EXPECT_NEAR(la, lb, 0.15 * lb);
  EXPECT_GT(a->counters().recoveries, 0u);
  EXPECT_GT(a->counters().max_cg_relative_residual, 0.0);
  // Bounds certified: every stored Σ~_ii − Σ_ii is PSD against the exact marginals.
  const core::ExactMarginals exact =
      core::ExactMarginals::compute(a->esdf().information().to_sparse(), 12);
  int checked = 0;
  for (int block = 1; block < a->esdf().num_blocks(); ++block) {
    if (!a->bounds().contains(block)) continue;
    double min_eig = 0.0;
    EXPECT_TRUE(
        core::is_conservative(a->bounds().bound(block), exact.marginal(block), 1e-9, &min_eig))
        << "state " << block << " min eigenvalue " << min_eig;
    ++checked;
  }
  EXPECT_GT(checked, 50);
}

}  // namespace
}  // namespace nav::daemon
