// Registration results keyed by frame pair (navigation/registration_table.h).
#include "nav/core/navigation/registration_table.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace nav::core {

bool RegistrationTable::insert(const Registration& r) {
  RegistrationResult result;
  result.success = r.success;
  result.z = r.z;
  result.covariance = r.covariance;
  result.overlap_fraction = r.overlap_fraction;
  result.is_outlier = r.is_outlier;
  result.available_us = r.available_us;
  if (r.frame_id_i >= r.frame_id_j) {
    throw std::invalid_argument("registration: frame_id_i (" + std::to_string(r.frame_id_i) +
                                ") must be smaller than frame_id_j (" +
                                std::to_string(r.frame_id_j) + ")");
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
