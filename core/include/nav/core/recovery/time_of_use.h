#pragma once
// Tightness and conservativeness of the bounds at the time of use (Eustice et al., RSS 2005,
// Sec. IV and Fig. 3): at a step where link proposal is about to run, every stored bound
// B_ii, the robot bound and every proposal joint [Σ_rr Σ_ri; Σ_ir B_ii] (bounds.h propose())
// are compared with the exact marginals of the current Λ; and for each state i the first-order
// relative-pose covariance of x_ri = (-)x_r (+) x_i under our joint and under the Markov
// blanket's (markov_blanket.h) is compared with the exact one by the log-det ratio of Fig. 3.
//
// Algorithm: one sparse Cholesky factorisation and selected inversion of Λ (exact_marginals.h)
// gives every Σ_ii; one solve with its factor for the d right-hand sides E_r gives the exact
// robot column Σ_*r and with it every exact joint (r, i). Cost: a factorisation and a selected
// inversion of the whole map, plus O(d) per state (and a Markov blanket per state when asked):
// a measurement tool, not something the filter thread runs on a vehicle.
//
// A pair where x_r, x_i or x_ri sits at pitch +-90 deg (geometry/rotation.h pitch_is_singular)
// has no relative-pose value, as the roll-pitch-heading Jacobian does not exist there; its
// bound and joint are still checked (counted in relative_pairs_singular).

#include <limits>
#include <vector>

#include "nav/core/filter/esdf.h"
#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/state_recovery.h"

namespace nav::core {

struct TimeOfUseOptions {
  double tolerance = 1e-9;     ///< is_conservative()'s relative tolerance (consistency.h)
  bool markov_blanket = true;  ///< also the Markov blanket's relative-pose ratio (slow)
};

/// Fig. 3's value of one pair (robot, state) at one check.
struct TimeOfUsePair {
  int check = 0;  ///< TimeOfUseStats::checks when it was made (1-based)
  int state = 0;  ///< i
  double ours = 0.0;  ///< log det(relative pose: ours / exact)
  double markov_blanket = std::numeric_limits<double>::quiet_NaN();  ///< blanket / exact
};

/// Accumulated over every check_time_of_use() call.
struct TimeOfUseStats {
  int checks = 0;
  int bounds_checked = 0, bounds_conservative = 0;
  int joints_checked = 0, joints_conservative = 0;
  int markov_blanket_overconfident = 0;  ///< pairs whose blanket relative pose is not >= exact
  int relative_pairs_singular = 0;       ///< pairs without a Fig. 3 value (file comment)
  /// Smallest eigenvalue of (ours - exact) over every bound and joint checked.
  double worst_min_eigenvalue = std::numeric_limits<double>::infinity();
  std::vector<TimeOfUsePair> pairs;  ///< every pair with a Fig. 3 value, in check order

  std::vector<double> ours() const;            ///< pairs[].ours
  std::vector<double> markov_blanket() const;  ///< pairs[].markov_blanket where computed

  double bounds_conservative_fraction() const;  ///< NaN before a check
  double joints_conservative_fraction() const;  ///< NaN before a check
};

/// Checks the bounds and proposal joints of `bounds` with the cross-covariances of `recovery`
/// (as link proposal uses them) against the exact marginals of `filter`'s current Λ, at the
/// means of `filter`; block 0 is the robot. Pose rows are the first 6 of each d-dim block
/// (d >= 6). Throws std::runtime_error when Λ is not positive definite (exact_marginals.h).
void check_time_of_use(const Esdf& filter, const CovarianceBounds& bounds,
                       const StateRecovery& recovery, const TimeOfUseOptions& options,
                       TimeOfUseStats& stats);

}  // namespace nav::core
