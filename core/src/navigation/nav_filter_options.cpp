// NavFilterOptions' checks (navigation/nav_filter_options.h).
#include "nav/core/navigation/nav_filter_options.h"

#include <stdexcept>
#include <string>

namespace nav::core {

NavFilterOptions validated(NavFilterOptions o) {
  if (!(o.max_predict_step_s > 0.0) ||
      !(o.min_predict_step_s >= 0.0 && o.min_predict_step_s < o.max_predict_step_s) ||
      !(o.default_altitude_m > 0.0) || !(o.camera_gate_chi2 > 0.0) ||
      !(o.initial_xy_sigma_m > 0.0) || !(o.initial_velocity_sigma_mps > 0.0) ||
      !(o.initial_rate_sigma_radps > 0.0)) {
    throw std::invalid_argument(
        "NavFilterOptions: max_predict_step_s, default_altitude_m, camera_gate_chi2 and the "
        "initial sigmas must be > 0, min_predict_step_s in [0, max_predict_step_s)");
  }
  if (!(o.recovery_handoff_s >= 0.0 && o.recovery_handoff_s <= 3600.0)) {
    throw std::invalid_argument("NavFilterOptions: recovery_handoff_s must be in [0, 3600] s, is " +
                                std::to_string(o.recovery_handoff_s));
  }
  return o;
}

}  // namespace nav::core
