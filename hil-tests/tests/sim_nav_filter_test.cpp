// A simulated dive through navd's whole measurement path (dive-log source, sensor decoders,
// time-of-validity order, NavFilter with the oracle's registrations): dead reckoning drifts,
// camera links (loop closures included) pull the estimate back to the truth, and the gate
// rejects the injected outliers. This checks that the simulated data is consistent with the
// filter's models (mounts, frames, signs, clocks), not the filter itself.
//
// Known filter limit (not the data's): NavFilter diverges after a prediction of a few tens of
// µs (two sensors' times of validity 53 µs apart with this seed: heading at +69 µs, altimeter
// at +122 µs; the constant-velocity Q ~ dt^3 makes Q^-1 huge in the information form). Until
// it merges or skips such steps, this test moves a measurement less than kMergeUs after the
// previous one onto the previous one's time.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "nav/core/navigation/nav_filter.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/filter/recovery_worker.h"
#include "nav/daemon/sources/dive_log_source.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

struct FilterRun {
  double final_xy_error_m = 0.0, max_xy_error_m = 0.0;
  daemon::NavFilterCounters counters;
};

FilterRun run_filter(const std::filesystem::path& dir, bool links, bool recovery_thread = true) {
  const daemon::NavdConfig cfg = daemon::load_config_file((dir / "config.yaml").string());
  const std::string log = (dir / "dive.lcmlog").string();
  const daemon::RegistrationTable table = daemon::load_registrations(log);
  const std::vector<daemon::Measurement> all = time_ordered_measurements(log, cfg);
  daemon::NavFilterOptions fo = daemon::filter_options_from_config(cfg);
  fo.propose_links = links;
  fo.recovery_thread = recovery_thread;
  if (recovery_thread) fo.recovery_executor = daemon::threaded_recovery_executor();
  daemon::NavFilter filter(fo, &table);
  constexpr std::int64_t kMergeUs = 1000;
  std::int64_t last_us = 0;
  for (daemon::Measurement m : all) {
    const std::int64_t t_us = daemon::validity_us(m);
    if (t_us > last_us && t_us - last_us < kMergeUs)
      std::visit([&](auto& x) { x.time.validity_us = last_us; }, m);
    last_us = daemon::validity_us(m);
    const core::Status s = filter.process(m);
    EXPECT_TRUE(s.ok()) << s.to_string();
    if (!s.ok()) break;
  }
  EXPECT_TRUE(filter.finish().ok());
  const auto images = read_csv(dir / "images.csv");
  FilterRun r;
  r.counters = filter.counters();
  for (const daemon::ImageRecord& im : filter.images()) {
    const auto& truth = images.at(im.frame_id);
    const double e = std::hypot(im.robot_mean[0] - truth[2], im.robot_mean[1] - truth[3]);
    r.max_xy_error_m = std::max(r.max_xy_error_m, e);
    r.final_xy_error_m = e;
  }
  return r;
}

TEST(SimNavFilter, LinksBoundTheDriftOfDeadReckoning) {
  const auto dir = scratch_dir("filter");
  SimOptions o = sim_options(dir, 4, 150);
  simulate_dive(o, sim_config_path().string());
  const FilterRun dr = run_filter(dir, false);
  const FilterRun slam = run_filter(dir, true);
  std::printf(
      "dead reckoning: final %.3f m, max %.3f m; SLAM: final %.3f m, max %.3f m; "
      "links proposed %llu accepted %llu gated %llu, outliers rejected %llu accepted %llu\n",
      dr.final_xy_error_m, dr.max_xy_error_m, slam.final_xy_error_m, slam.max_xy_error_m,
      static_cast<unsigned long long>(slam.counters.links_proposed),
      static_cast<unsigned long long>(slam.counters.links_accepted),
      static_cast<unsigned long long>(slam.counters.links_gated),
      static_cast<unsigned long long>(slam.counters.outliers_rejected),
      static_cast<unsigned long long>(slam.counters.outliers_accepted));
  EXPECT_EQ(slam.counters.images, 150u);
  EXPECT_GT(slam.counters.links_accepted, 150u);
  EXPECT_LT(slam.max_xy_error_m, 1.0);
  EXPECT_LT(slam.max_xy_error_m, dr.max_xy_error_m);
  EXPECT_EQ(slam.counters.outliers_accepted, 0u);
}

// The recovery thread (opt-in: filter.recovery_thread) against synchronous recovery on the same
// simulated dive: stated tolerance 5 cm on the final and the largest xy error, link decisions
// within 3 %, no outlier accepted by either.
TEST(SimNavFilter, RecoveryThreadAgreesWithSynchronousRecovery) {
  const auto dir = scratch_dir("filter-thread");
  SimOptions o = sim_options(dir, 4, 100);
  simulate_dive(o, sim_config_path().string());
  const FilterRun threaded = run_filter(dir, true, true);
  const FilterRun sync = run_filter(dir, true, false);
  std::printf(
      "thread: final %.3f m, max %.3f m, links %llu; synchronous: final %.3f m, max "
      "%.3f m, links %llu\n",
      threaded.final_xy_error_m, threaded.max_xy_error_m,
      static_cast<unsigned long long>(threaded.counters.links_accepted), sync.final_xy_error_m,
      sync.max_xy_error_m, static_cast<unsigned long long>(sync.counters.links_accepted));
  EXPECT_NEAR(threaded.final_xy_error_m, sync.final_xy_error_m, 0.05);
  EXPECT_NEAR(threaded.max_xy_error_m, sync.max_xy_error_m, 0.05);
  const auto lt = static_cast<double>(threaded.counters.links_accepted);
  const auto ls = static_cast<double>(sync.counters.links_accepted);
  EXPECT_GT(ls, 100.0);
  EXPECT_NEAR(lt, ls, 0.03 * ls);
  EXPECT_EQ(threaded.counters.outliers_accepted, 0u);
  EXPECT_EQ(sync.counters.outliers_accepted, 0u);
  EXPECT_EQ(threaded.counters.recovery_failures, 0u);
}

}  // namespace
}  // namespace nav::sim::test
