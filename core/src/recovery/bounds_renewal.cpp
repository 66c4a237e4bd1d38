// renew_bounds (recovery/bounds_renewal.h).
#include "nav/core/recovery/bounds_renewal.h"

namespace nav::core {

Status renew_bounds(const RecoveryResult& result, const ExactMarginals* exact, int num_states,
                    CovarianceBounds& bounds, BoundsSnapshot* snapshot) {
  Status s = Status::Ok();
  if (exact != nullptr && result.refreshed) {
    s = bounds.refresh_exact(*exact, num_states);
  } else if (exact != nullptr && result.renewed_earlier) {
    s = bounds.refresh_exact(exact->marginals(), num_states, snapshot);
  }
  if (result.renewal_started) *snapshot = bounds.snapshot();
  return s;
}

}  // namespace nav::core
