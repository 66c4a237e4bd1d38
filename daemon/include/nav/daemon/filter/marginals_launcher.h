#pragma once
// The threaded core::MarginalsLauncher (nav/core/recovery/lagged_renewal.h): each renewal of the
// exact marginals runs on a thread of its own beside the filter thread, which takes it a fixed
// number of images later and waits there if it is not done, so the outputs are those of the
// inline default whatever the timing. A renewal that is never taken finishes and is discarded
// (the last handle's destruction waits for it).

#include "nav/core/recovery/lagged_renewal.h"

namespace nav::daemon {

core::MarginalsLauncher threaded_marginals_launcher();

}  // namespace nav::daemon
