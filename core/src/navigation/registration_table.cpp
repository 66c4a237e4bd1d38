// Registration results keyed by frame pair (navigation/registration_table.h).
#include "nav/core/navigation/registration_table.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace nav::core {

std::optional<std::string> registration_problem(const Registration& r) {
  const std::string pair =
      "registration " + std::to_string(r.frame_id_i) + "-" + std::to_string(r.frame_id_j) + ": ";
  if (r.frame_id_i >= r.frame_id_j) {
    return "registration: frame_id_i (" + std::to_string(r.frame_id_i) +
           ") must be smaller than frame_id_j (" + std::to_string(r.frame_id_j) + ")";
  }
  if (!r.success) return std::nullopt;  // a failure carries no measurement to check
  if (!r.z.allFinite()) return pair + "measurement is not finite";
  constexpr double kPi = std::numbers::pi;
  for (int k = 0; k < 5; ++k) {
    const double limit = k == 1 ? kPi / 2 : kPi;
    if (std::abs(r.z(k)) > limit) {
      return pair + "measurement component " + std::to_string(k) + " (" + std::to_string(r.z(k)) +
             " rad) is outside [-" + std::to_string(limit) + ", " + std::to_string(limit) + "]";
    }
  }
  const Eigen::Matrix<double, 5, 5>& P = r.covariance;
  if (!P.allFinite()) return pair + "covariance is not finite";
  // Judged on P scaled by its largest entry, so that huge finite entries (whose Frobenius norm
  // overflows to inf, and inf > 1e-9 * inf is false) cannot pass the symmetry test.
  const double scale = P.cwiseAbs().maxCoeff();
  if (scale == 0.0) return pair + "covariance is not positive definite";
  const Eigen::Matrix<double, 5, 5> S = P / scale;
  if ((S - S.transpose()).norm() > 1e-9 * S.norm()) return pair + "covariance is not symmetric";
  // Eigen's LLT only refuses a pivot <= 0: one that overflowed to NaN would pass, so the
  // factor must be finite too.
  const Eigen::LLT<Eigen::Matrix<double, 5, 5>> llt(P);
  if (llt.info() != Eigen::Success || !llt.matrixL().toDenseMatrix().allFinite()) {
    return pair + "covariance is not positive definite";
  }
  return std::nullopt;
}

bool RegistrationTable::insert(const Registration& r) {
  RegistrationResult result;
  result.success = r.success;
  result.z = r.z;
  result.covariance = r.covariance;
  result.overlap_fraction = r.overlap_fraction;
  result.is_outlier = r.is_outlier;
  result.available_us = r.available_us;
  if (const std::optional<std::string> problem = registration_problem(r)) {
    throw std::invalid_argument(*problem);
  }
  if (!results_.emplace(std::make_pair(r.frame_id_i, r.frame_id_j), result).second) return false;
  ++generation_;
  return true;
}

std::optional<RegistrationResult> RegistrationTable::find(std::int64_t a, std::int64_t b) const {
  const auto it = results_.find({std::min(a, b), std::max(a, b)});
  if (it == results_.end()) return std::nullopt;
  return it->second;
}

std::size_t RegistrationTable::outliers() const {
  return static_cast<std::size_t>(std::count_if(
      results_.begin(), results_.end(), [](const auto& kv) { return kv.second.is_outlier; }));
}

}  // namespace nav::core
