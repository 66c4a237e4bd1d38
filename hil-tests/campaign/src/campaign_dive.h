#pragma once
// The simulated dives the fault campaign and the soak play (navtool simulate's library,
// nav/sim/simulate.h): simulated once into a directory, then reused.
//
// Threads: any (one caller per directory).

#include <cstdint>
#include <filesystem>

namespace nav::campaign {

/// `dir` holding a dive of `images` images (seed `seed`, config `sim_config`), simulated unless
/// it already has truth.csv and dive.lcmlog. `dvl_dropouts` false: none of the simulator's
/// bottom-lock dropouts (the campaign's own outages only); true: the default 1.5 per hour.
std::filesystem::path simulated_dive(const std::filesystem::path& dir, int images,
                                     std::uint64_t seed, const std::filesystem::path& sim_config,
                                     bool dvl_dropouts);

}  // namespace nav::campaign
