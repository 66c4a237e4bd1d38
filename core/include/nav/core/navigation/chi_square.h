#pragma once
// Chi-square distribution for innovation gates: closed-form CDF for integer degrees of freedom
// and its inverse by bisection. Used to carry the config's 6-dof gate (filter.
// gating_chi2_threshold, "16.81 = chi2 99 % for 6 dof") over to the 5-dof camera link
// measurement at the same probability, so one config key sets both gates.
//
// CDF (Abramowitz & Stegun 26.4.4 / 26.4.5, integer k):
//   k even: P(x) = 1 - e^{-x/2} sum_{j=0}^{k/2-1} (x/2)^j / j!
//   k odd:  P(x) = erf(sqrt(x/2)) - sqrt(2x/pi) e^{-x/2} sum_{j=0}^{(k-3)/2} x^j / (3 5 ... (2j+1))

namespace nav::core {

/// P(X <= x) for X ~ chi2(dof), dof in [1, 100]; 0 for x <= 0. Throws std::invalid_argument
/// for dof out of range or a non-finite x.
double chi_square_cdf(double x, int dof);

/// The x with chi_square_cdf(x, dof) = probability (probability in (0, 1)), to 1e-12 relative.
double chi_square_quantile(double probability, int dof);

/// The gate for `to_dof` with the same tail probability as `threshold` has for `from_dof`
/// (e.g. 16.81 for 6 dof -> 15.09 for 5 dof, both at 99 %).
double equivalent_chi_square_gate(double threshold, int from_dof, int to_dof);

}  // namespace nav::core
