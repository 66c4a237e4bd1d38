#pragma once
// One fault scenario end to end (fault_campaign.h) and its verdict.
//
// Threads: run_scenario() starts the player's and the LCM listener's threads and joins them.

#include <cstdint>
#include <filesystem>
#include <string>

#include "nav/campaign/fault_campaign.h"
#include "scenario_metrics.h"

namespace nav::campaign {

struct ScenarioSetup {
  std::filesystem::path out_dir;   ///< the scenario writes out_dir/scenarios/<name>/
  std::filesystem::path dive_dir;  ///< the simulated dive played
  std::filesystem::path navd_path;
  std::string lcm_url;
  bool camera = false;  ///< the fake GigE camera may be served (private network namespace)
  std::uint64_t seed = 7;
  int give_up_s = 900;  ///< wall seconds before the playback is stopped
};

/// Plays the dive with the scenario's fault to a fresh navd and measures. Throws
/// std::runtime_error when navd or the player cannot be started.
ScenarioResult run_scenario(const FaultScenario& scenario, const ScenarioSetup& setup);

/// Sets pass / reason from the measurements (fault_campaign.h "Verdict").
void judge(const FaultScenario& scenario, ScenarioResult& result);

}  // namespace nav::campaign
