// NavFilter with the exact marginals renewed beside the filter (filter.recovery_renewal_lag:
// core/recovery/lagged_renewal.h, daemon/filter/marginals_launcher.h) on the synthetic dive of
// support/synthetic_dive.h: the whole filter state is bit-identical whether the renewals run on
// a thread or inline on the filter thread; the bounds stay conservative against the exact
// marginals at the end; and the lagged renewals do renew them (without them the bounds of the
// states stay far looser).
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cstdio>
#include <vector>

#include "nav/core/recovery/consistency.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/daemon/filter/marginals_launcher.h"
#include "support/nav_filter_fixture.h"

namespace nav::daemon {
namespace {

using nav::testing::Bytes;
using nav::testing::encode;

/// The kept factor with exact marginals renewed every `interval` images, taken `lag` images
/// later, and at once as the map's size passes the powers of 1 + `growth` (0: never).
struct Fixture : nav::testing::NavFilterFixture {
  Fixture(int lag, int interval, double growth = 0.0) : NavFilterFixture(160.0) {
    config.filter.recovery_preconditioner = core::RecoveryPreconditioner::kFactor;
    config.filter.recovery_keep_factor_equal = true;
    config.filter.recovery_refresh_interval = interval;
    config.filter.recovery_renewal_lag = lag;
    config.filter.recovery_refresh_growth = growth;
    options = filter_options_from_config(config);
  }
};

std::unique_ptr<NavFilter> run_all(const Fixture& fx, const NavFilterOptions& o) {
  auto f = fx.make(o);
  for (const Measurement& m : fx.dive.measurements) EXPECT_TRUE(f->process(m).ok());
  EXPECT_TRUE(f->finish().ok());
  EXPECT_EQ(f->counters().recovery_failures, 0u);
  return f;
}

double log_det(const Eigen::MatrixXd& spd) {
  const Eigen::LLT<Eigen::MatrixXd> llt(spd);
  return 2.0 * llt.matrixLLT().diagonal().array().log().sum();
}

/// Median over the states of log det(bound) − log det(exact marginal), both of the end; every
/// bound checked conservative on the way.
double median_logdet_ratio(const NavFilter& f) {
  const core::ExactMarginals exact =
      core::ExactMarginals::compute(f.esdf().information().to_sparse(), 12);
  std::vector<double> ratios;
  for (int b = 1; b < f.esdf().num_blocks(); ++b) {
    double min_eig = 0.0;
    EXPECT_TRUE(core::is_conservative(f.bounds().bound(b), exact.marginal(b), 1e-9, &min_eig))
        << "state " << b << " min eigenvalue " << min_eig;
    ratios.push_back(log_det(f.bounds().bound(b)) - log_det(exact.marginal(b)));
  }
  std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
  return ratios[ratios.size() / 2];
}

TEST(NavFilterLaggedRenewal, ThreadedAndInlineRenewalsGiveTheSameFilter) {
  const Fixture fx(3, 10, 0.25);
  ASSERT_TRUE(static_cast<bool>(fx.options.renewal_launcher));  // navd's: a thread
  NavFilterOptions inline_options = fx.options;
  inline_options.renewal_launcher = nullptr;
  const Bytes threaded = encode(*run_all(fx, fx.options));
  EXPECT_EQ(threaded, encode(*run_all(fx, inline_options)));
  EXPECT_EQ(threaded, encode(*run_all(fx, fx.options)));
}

TEST(NavFilterLaggedRenewal, BoundsStayConservativeAndAreRenewed) {
  const Fixture lagged(3, 10), synchronous(0, 10), first_image_only(0, 100000);
  const auto f = run_all(lagged, lagged.options);
  ASSERT_GT(f->esdf().num_blocks(), 15);
  const double ratio = median_logdet_ratio(*f);
  const double ratio_synchronous = median_logdet_ratio(*run_all(synchronous, synchronous.options));
  const double ratio_once =
      median_logdet_ratio(*run_all(first_image_only, first_image_only.options));
  std::printf(
      "median log det(bound / exact) at the end: lagged %.3g, synchronous %.3g, renewed "
      "at the first image only %.3g\n",
      ratio, ratio_synchronous, ratio_once);
  EXPECT_LT(ratio, 0.5 * ratio_once);
}

}  // namespace
}  // namespace nav::daemon
