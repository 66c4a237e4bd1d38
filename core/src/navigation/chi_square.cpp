// Chi-square CDF and quantile for integer degrees of freedom (see chi_square.h).
#include "nav/core/navigation/chi_square.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace nav::core {
namespace {

void check_dof(int dof, const char* where) {
  if (dof < 1 || dof > 100) {
    throw std::invalid_argument(std::string(where) + ": degrees of freedom " +
                                std::to_string(dof) + " outside [1, 100]");
  }
}

}  // namespace

double chi_square_cdf(double x, int dof) {
  check_dof(dof, "chi_square_cdf");
  if (!std::isfinite(x)) throw std::invalid_argument("chi_square_cdf: x is not finite");
  if (x <= 0.0) return 0.0;
  const double half = 0.5 * x;
  double sum = 0.0;
  double term = 1.0;
  if (dof % 2 == 0) {
    for (int j = 0; j < dof / 2; ++j) {
      if (j > 0) term *= half / j;
      sum += term;
    }
    return 1.0 - std::exp(-half) * sum;
  }
  for (int j = 0; j <= (dof - 3) / 2; ++j) {
    if (j > 0) term *= x / (2 * j + 1);
    sum += term;
  }
  const double tail = dof >= 3 ? std::sqrt(2.0 * x / std::numbers::pi) * std::exp(-half) * sum : 0.0;
  return std::erf(std::sqrt(half)) - tail;
}

double chi_square_quantile(double probability, int dof) {
  check_dof(dof, "chi_square_quantile");
  if (!(probability > 0.0 && probability < 1.0)) {
    throw std::invalid_argument("chi_square_quantile: probability " + std::to_string(probability) +
                                " outside (0, 1)");
  }
  double lo = 0.0, hi = dof + 10.0;
  while (chi_square_cdf(hi, dof) < probability) hi *= 2.0;
  for (int it = 0; it < 200 && hi - lo > 1e-12 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (chi_square_cdf(mid, dof) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double equivalent_chi_square_gate(double threshold, int from_dof, int to_dof) {
  const double p = chi_square_cdf(threshold, from_dof);
  if (!(p > 0.0 && p < 1.0)) {
    throw std::invalid_argument("equivalent_chi_square_gate: threshold " +
                                std::to_string(threshold) + " for " + std::to_string(from_dof) +
                                " dof has tail probability 0 or 1");
  }
  return chi_square_quantile(p, to_dof);
}

}  // namespace nav::core
