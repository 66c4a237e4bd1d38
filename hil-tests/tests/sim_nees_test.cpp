// Monte-Carlo consistency of the SLAM filter on the simulated survey: over
// kSeeds small dives, the newest delayed state's final mean (direct solve) against the true
// pose of its image, normalised by its exact marginal (CHOLMOD + Takahashi, replay analyse()).
// The seed-averaged 6-dof NEES must lie in the two-sided 95 % chi-square interval of
// kSeeds x 6 dof divided by kSeeds; each component's averaged NEES in that of kSeeds x 1 dof.
// The dives run through the replay library in-process: dive-log source, sensor decoders, time
// ordering, NavFilter, exactly as `navtool replay`, with config/sim.yaml as shipped (its process
// noise, nothing tuned here) and the simulator's default errors, DVL dropouts included. The
// full-size survey (866 images x 20 seeds) is `hil-tests/nees-seeds` (hil-tests/README.md).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>

#include "nav/core/geometry/rotation.h"
#include "nav/core/navigation/chi_square.h"
#include "nav/daemon/replay/dive_replay.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

constexpr int kSeeds = 20;
constexpr int kImages = 30;
constexpr std::array<const char*, 6> kComponents = {"x", "y", "z", "roll", "pitch", "heading"};

struct PoseNees {
  double nees6 = 0.0;
  std::array<double, 6> component{};  ///< e_i^2 / Σ_ii
  std::uint64_t links_gated = 0, links_tested = 0, outliers_accepted = 0, outliers_rejected = 0;
};

/// Two-sided `confidence` interval of the mean of `seeds` independent chi2(dof) values
/// (chi_square_quantile up to 100 dof, Wilson-Hilferty above: relative error < 0.1 % there).
std::pair<double, double> mean_chi2_interval(int dof, int seeds, double confidence) {
  const int n = dof * seeds;
  const double lo_p = 0.5 * (1.0 - confidence), hi_p = 1.0 - lo_p;
  if (n <= 100)
    return {core::chi_square_quantile(lo_p, n) / seeds, core::chi_square_quantile(hi_p, n) / seeds};
  const double z = 1.959963984540054;  // 97.5 % normal quantile (95 % two-sided)
  EXPECT_NEAR(confidence, 0.95, 1e-12) << "Wilson-Hilferty branch has z for 95 % only";
  const double c = 2.0 / (9.0 * n);
  const auto wh = [&](double zz) { return n * std::pow(1.0 - c + zz * std::sqrt(c), 3) / seeds; };
  return {wh(-z), wh(z)};
}

PoseNees newest_state_nees(std::uint64_t seed, const SensorErrorOptions& errors) {
  const auto dir = scratch_dir("nees_" + std::to_string(seed));
  SimOptions o = sim_options(dir, seed, kImages);
  o.sensor_errors = errors;
  simulate_dive(o, sim_config_path().string());
  // The dive's config.yaml is config/sim.yaml as shipped (simulate_dive copies it).
  const daemon::NavdConfig cfg = daemon::load_config_file((dir / "config.yaml").string());
  daemon::ReplayOptions ro;
  ro.dead_reckoning = false;
  daemon::ReplayRun run = daemon::run_replay((dir / "dive.lcmlog").string(), cfg, ro);
  EXPECT_TRUE(run.error.empty()) << "seed " << seed << ": " << run.error;
  const daemon::ReplayAnalysis a = daemon::analyse(*run.slam);
  EXPECT_TRUE(a.error.empty()) << "seed " << seed << ": " << a.error;
  const daemon::StateCheck* newest = nullptr;
  for (const daemon::StateCheck& s : a.states)
    if (s.image && (!newest || s.image->frame_id > newest->image->frame_id)) newest = &s;
  PoseNees r;
  if (!newest) {
    ADD_FAILURE() << "seed " << seed << ": no delayed state";
    return r;
  }
  const auto images = read_csv(dir / "images.csv");
  const auto& truth = images.at(newest->image->frame_id);  // frame_id,t_us,x,y,z,r,p,h,...
  Eigen::Matrix<double, 6, 1> e;
  for (int i = 0; i < 6; ++i) e[i] = newest->mean[i] - truth[static_cast<std::size_t>(2 + i)];
  for (int i = 3; i < 6; ++i) e[i] = core::wrap_angle(e[i]);
  r.nees6 = e.dot(newest->exact.ldlt().solve(e));
  for (int i = 0; i < 6; ++i)
    r.component[static_cast<std::size_t>(i)] = e[i] * e[i] / newest->exact(i, i);
  const daemon::NavFilterCounters& c = run.slam->counters();
  r.links_gated = c.links_gated;
  r.links_tested = c.links_accepted + c.links_gated;
  r.outliers_accepted = c.outliers_accepted;
  r.outliers_rejected = c.outliers_rejected;
  return r;
}

struct MonteCarlo {
  double nees6 = 0.0;
  std::array<double, 6> component{};
  std::uint64_t links_gated = 0, links_tested = 0, outliers_accepted = 0, outliers_rejected = 0;
  /// Good (not injected-outlier) links gated / good links tested.
  double good_gated_fraction() const {
    const auto good = static_cast<double>(links_tested - outliers_accepted - outliers_rejected);
    return static_cast<double>(links_gated - outliers_rejected) / good;
  }
};

MonteCarlo monte_carlo(const SensorErrorOptions& errors) {
  MonteCarlo m;
  for (int s = 1; s <= kSeeds; ++s) {
    const PoseNees p = newest_state_nees(static_cast<std::uint64_t>(s), errors);
    m.nees6 += p.nees6 / kSeeds;
    for (std::size_t i = 0; i < 6; ++i) m.component[i] += p.component[i] / kSeeds;
    m.links_gated += p.links_gated;
    m.links_tested += p.links_tested;
    m.outliers_accepted += p.outliers_accepted;
    m.outliers_rejected += p.outliers_rejected;
  }
  const auto [lo6, hi6] = mean_chi2_interval(6, kSeeds, 0.95);
  std::printf("%d seeds x %d images: mean 6-dof NEES %.2f (95 %% [%.2f, %.2f]); per component",
              kSeeds, kImages, m.nees6, lo6, hi6);
  for (std::size_t i = 0; i < 6; ++i) std::printf(" %s %.2f", kComponents[i], m.component[i]);
  std::printf(
      "; links gated %llu of %llu tested, outliers rejected %llu accepted %llu, good links "
      "gated %.2f %%\n",
      static_cast<unsigned long long>(m.links_gated),
      static_cast<unsigned long long>(m.links_tested),
      static_cast<unsigned long long>(m.outliers_rejected),
      static_cast<unsigned long long>(m.outliers_accepted), 100.0 * m.good_gated_fraction());
  return m;
}

/// The default sensor errors without DVL bottom-lock losses.
SensorErrorOptions without_dropouts(SensorErrorOptions e) {
  e.dvl_dropouts_per_hour = 0.0;
  return e;
}

// The default survey's errors, DVL dropouts included: a 30-image dive (235 s) gets at least one
// 10-40 s loss (sensor_streams.h), far more than the 1.5 per hour of the full survey.
TEST(SimNees, NewestDelayedStateIsConsistentOverTwentySeeds) {
  const MonteCarlo m = monte_carlo(SensorErrorOptions{});
  const auto [lo6, hi6] = mean_chi2_interval(6, kSeeds, 0.95);
  EXPECT_GE(m.nees6, lo6);
  EXPECT_LE(m.nees6, hi6);
  const double hi1 = mean_chi2_interval(1, kSeeds, 0.95).second;
  // Per component only the upper end (not overconfident).
  for (std::size_t i = 0; i < 6; ++i) EXPECT_LE(m.component[i], hi1) << kComponents[i];
  EXPECT_EQ(m.outliers_accepted, 0u);
  EXPECT_GT(m.outliers_rejected, 0u);
  // After a loss in a turn the vehicle slows to ~1 % surge (simulate.cpp surge_command) while
  // the constant-velocity model holds its speed: dead reckoning runs metres along track, beyond
  // the process noise (seed 19: 8.3 m against 2.65 m 1-sigma), and good links to it are gated.
  // Measured 6.5 % (8.2 % before links were linearised at the iterated point, nav_filter.h);
  // bounded here, the 2 % target is checked with bottom lock below.
  EXPECT_LE(m.good_gated_fraction(), 0.08);
}

// With bottom lock throughout, the 99 % gate rejects about 1 % of the good links.
TEST(SimNees, WithBottomLockFewGoodLinksAreGated) {
  const MonteCarlo m = monte_carlo(without_dropouts(SensorErrorOptions{}));
  EXPECT_LE(m.nees6, mean_chi2_interval(6, kSeeds, 0.95).second);
  EXPECT_EQ(m.outliers_accepted, 0u);
  EXPECT_LE(m.good_gated_fraction(), 0.02) << "gate at 99 %: ~1 % of good links expected";
}

// The uncalibrated vehicle (navtool simulate --sensor-biases): the constant offsets the filter
// does not model make it overconfident; measured and printed, and it must stay outside.
TEST(SimNees, UncalibratedBiasesMakeTheFilterOverconfident) {
  const MonteCarlo m = monte_carlo(without_dropouts(SensorErrorOptions::with_sensor_biases()));
  EXPECT_GT(m.nees6, mean_chi2_interval(6, kSeeds, 0.95).second);
  EXPECT_EQ(m.outliers_accepted, 0u);
}

}  // namespace
}  // namespace nav::sim::test
