// Simulated dives of the campaign and the soak; see campaign_dive.h.
#include "campaign_dive.h"

#include "nav/sim/simulate.h"

namespace nav::campaign {

std::filesystem::path simulated_dive(const std::filesystem::path& dir, int images,
                                     std::uint64_t seed, const std::filesystem::path& sim_config,
                                     bool dvl_dropouts) {
  if (std::filesystem::exists(dir / "truth.csv") && std::filesystem::exists(dir / "dive.lcmlog")) {
    return dir;
  }
  sim::SimOptions so;
  so.out_dir = dir.string();
  so.seed = seed;
  so.mission.images = images;
  if (!dvl_dropouts) so.sensor_errors.dvl_dropouts_per_hour = 0.0;
  (void)sim::simulate_dive(so, sim_config.string());
  return dir;
}

}  // namespace nav::campaign
