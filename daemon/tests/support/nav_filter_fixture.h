#pragma once
// NavFilter on the synthetic dive of support/synthetic_dive.h, for tests that compare whole
// filter states (checkpoints, the recovery thread): the shipped config/sim.yaml (ctest runs in
// the source directory) with block-Jacobi recovery, the dive, the config's filter options, and
// the filter's whole state as its checkpoint bytes (ESDF, bounds, warm start, NAVF: images,
// links, counters, ...).
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <vector>

#include "nav/core/serialization/sections.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/checkpoint/nav_filter_checkpoint.h"
#include "nav/core/navigation/nav_filter.h"
#include "synthetic_dive.h"

namespace nav::testing {

using Bytes = std::vector<std::uint8_t>;

/// The block-Jacobi recovery instead of config/sim.yaml's kept factor, for tests of bit-identical
/// continuation: a restored kept factor starts from a fresh factorisation, equal to the one it
/// replaces only up to rounding (docs/formats.md "Checkpoints"), and a child forked after the
/// parent ran CHOLMOD hangs in libgomp at its first factorisation (seen in gdb).
inline void use_block_jacobi(daemon::NavdConfig& config) {
  config.filter.recovery_preconditioner = core::RecoveryPreconditioner::kBlockJacobi;
  config.filter.recovery_keep_factor_equal = false;
  config.filter.recovery_renewal_lag = 0;  // a setting of the kept factor only
}

struct NavFilterFixture {
  explicit NavFilterFixture(double duration_s) {
    config = synthetic_dive_config();
    use_block_jacobi(config);  // the bit-identical continuation these tests compare
    SyntheticDiveOptions o;
    o.duration_s = duration_s;
    dive = make_synthetic_dive(config, o);
    options = daemon::filter_options_from_config(config);
  }
  std::unique_ptr<daemon::NavFilter> make(const daemon::NavFilterOptions& o) const {
    return std::make_unique<daemon::NavFilter>(o, &dive.registrations);
  }
  std::unique_ptr<daemon::NavFilter> make() const { return make(options); }

  daemon::NavdConfig config;
  SyntheticDive dive;
  daemon::NavFilterOptions options;
};

/// The whole filter state as its checkpoint bytes.
inline Bytes encode(const daemon::NavFilter& f) {
  core::SectionWriter w;
  EXPECT_TRUE(daemon::add_nav_filter_sections(f, &w).ok());
  return w.finish();
}

}  // namespace nav::testing
