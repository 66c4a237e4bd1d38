// Shared checks of the measurement models (measurement.h).

#include "nav/core/models/measurement.h"

#include <stdexcept>
#include <string>

namespace nav::core {

void require_block_size(Eigen::Index size, bool need_velocity, const char* model) {
  const bool ok = need_velocity ? size == 12 : (size == 6 || size == 12);
  if (ok) return;
  throw std::invalid_argument(std::string(model) + ": state block has " + std::to_string(size) +
                              " elements, expected " + (need_velocity ? "12" : "6 or 12"));
}

}  // namespace nav::core
