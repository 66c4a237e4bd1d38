#pragma once
// The bounds' side of a recovery's renewal of the exact marginals (state_recovery.h,
// RecoveryResult): a refresh of this Λ resets every bound to its marginals; a lagged renewal
// (lagged_renewal.h) resets them from the Λ of its snapshot, whose BoundsSnapshot was taken when
// it started (bounds.h refresh_exact). Shared by NavFilter and the pose-graph replay.

#include "nav/core/recovery/bounds.h"
#include "nav/core/recovery/exact_marginals.h"
#include "nav/core/recovery/recovery_options.h"
#include "nav/core/status.h"

namespace nav::core {

/// Applies `result`'s renewal to `bounds` (a filter of `num_states` blocks) from `exact`
/// (StateRecovery::refreshed_marginals(), may be null), then records `*snapshot` when the
/// result started a lagged renewal. Call after the solve, before set_recovery. The error of
/// refresh_exact, the bounds unchanged by it.
Status renew_bounds(const RecoveryResult& result, const ExactMarginals* exact, int num_states,
                    CovarianceBounds& bounds, BoundsSnapshot* snapshot);

}  // namespace nav::core
