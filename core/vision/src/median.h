#pragma once
// The median of the vision library's robust statistics (private to core/vision/src).
#include <algorithm>
#include <cstddef>
#include <vector>

namespace nav::vision::detail {

/// The upper median v[n/2] of the sorted values (for even n the larger middle one); 0 when
/// empty. Takes a copy: the order of the caller's values is kept.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace nav::vision::detail
