// The soak's fits (soak_analysis.h) against values computed by hand: a least-squares line
// through exact points, the RSS growth and CPU per dive hour of synthetic samples, warm-up
// samples left out.
#include <gtest/gtest.h>

#include "../campaign/src/soak_analysis.h"

namespace {

using nav::campaign::SoakSample;

TEST(SoakAnalysis, FitLineRecoversAnExactLineAndDegenerateInputs) {
  const auto [a, b] = nav::campaign::fit_line({0, 1, 2, 3}, {1, 3, 5, 7});
  EXPECT_NEAR(a, 1.0, 1e-12);
  EXPECT_NEAR(b, 2.0, 1e-12);
  // Noise symmetric about y = 4 - x: the same line.
  const auto [a2, b2] = nav::campaign::fit_line({0, 0, 2, 2}, {3.5, 4.5, 1.5, 2.5});
  EXPECT_NEAR(a2, 4.0, 1e-12);
  EXPECT_NEAR(b2, -1.0, 1e-12);
  const auto [a3, b3] = nav::campaign::fit_line({1, 1}, {2, 4});  // one distinct x
  EXPECT_NEAR(a3, 3.0, 1e-12);
  EXPECT_EQ(b3, 0.0);
}

TEST(SoakAnalysis, GrowthCpuRateAndDescriptorsAfterWarmup) {
  std::vector<SoakSample> s;
  for (int i = 0; i <= 10; ++i) {
    SoakSample x;
    x.dive_h = 0.5 * i;                                 // 0 .. 5 dive hours
    x.rss_mb = i == 0 ? 10.0 : 100.0 + 0.4 * x.dive_h;  // the first sample is warm-up
    x.cpu_s = 30.0 * x.dive_h;                          // 30 CPU s per dive hour
    x.fds = i == 0 ? 3 : 20 + i % 2;
    x.queue_depth = i == 3 ? 7 : 0;
    x.late_measurements = i;
    s.push_back(x);
  }
  const nav::campaign::SoakSummary r = nav::campaign::analyse_soak(s, 0.25);
  EXPECT_EQ(r.samples, 11);
  EXPECT_DOUBLE_EQ(r.dive_hours, 5.0);
  EXPECT_NEAR(r.rss_slope_mb_per_dive_h, 0.4, 1e-9);
  EXPECT_NEAR(r.rss_first_mb, 100.2, 1e-9);
  EXPECT_NEAR(r.rss_last_mb, 102.0, 1e-9);
  EXPECT_NEAR(r.rss_growth_percent, 100.0 * 1.8 / 100.2, 1e-9);
  EXPECT_NEAR(r.cpu_s_per_dive_h, 30.0, 1e-9);
  EXPECT_NEAR(r.cpu_slope_per_dive_h, 0.0, 1e-9);
  EXPECT_EQ(r.fds_min, 20);
  EXPECT_EQ(r.fds_max, 21);
  EXPECT_EQ(r.max_queue_depth, 7);
  EXPECT_EQ(r.late_measurements, 10);
}

}  // namespace
