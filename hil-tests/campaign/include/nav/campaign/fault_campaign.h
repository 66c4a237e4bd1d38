#pragma once
// The fault campaign (docs/faults.md, `navtool fault-campaign`): every scenario of
// fault_scenarios.h is one run of the real navd binary in live mode (--checkpoints) on a
// simulated dive that the HIL player (nav/hil/dive_player.h) plays at real time (navd dates
// bytes by their arrival, so only speed 1 keeps the pose meaningful), over LCM udpm ttl=0 in a
// private network (and mount) namespace when this process may create one (root: the campaign
// then serves the camera with Aravis' fake GigE camera on its own lo, so navd takes images and
// recovers covariances). What navd publishes is measured against the dive's truth.csv:
//   detected_after_s   first NAVD_HEALTH (by its utime) after the fault's start meeting the
//                      scenario's Detector, minus the start (both CLOCK_REALTIME); -1: never;
//   max_xy_error_m     worst horizontal error of NAVD_SOLUTION from the fault to the dive's end
//                      (time of validity mapped to dive time with the player's mapping);
//   nees_*             mean horizontal NEES e' P_xy^-1 e of the published solutions (2 DOF,
//                      expected 2) before / during / after the fault window (-1: no
//                      solution in that window);
//   sigma_xy_*_m       sqrt(trace P_xy) published at the window's start and end;
//   delayed_states_lost  kill_restart: delayed states of the last solution before SIGKILL
//                      minus those of the first after the restart (the checkpoint's age);
//   map_xy_rms_m       RMS horizontal error of the last NAVD_BOUNDS_SNAPSHOT's delayed-state
//                      means against the truth at their image times (the map after the fault).
// Verdict (pass): navd alive at the end (or restarted, kill_restart); detected within 3 s where
// a Detector is set; mean NEES during and after <= 6 (the 95 % chi-square bound of one 2-DOF
// sample: lenient, the samples are correlated); XY sigma grew where uncertainty_must_grow;
// no delayed state lost; where the scenario asks: the sensor reconnected by itself and was
// read after the window (camera_vanish), no measurement dropped as late or for a full queue
// (navd's exit summary: dropped_late, queue_dropped). `reason` lists each failed criterion.
//
// Threads: run_campaign() enters the namespaces first, so call it before starting threads.

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nav/campaign/fault_scenarios.h"

namespace nav::campaign {

struct CampaignOptions {
  std::filesystem::path out_dir;     ///< dives, per-scenario logs, faults.md, faults.json
  std::filesystem::path navd_path;   ///< the navd binary
  std::filesystem::path sim_config;  ///< config/sim.yaml
  bool short_version = false;        ///< the CI's 3 scenarios on a 43-s dive
  std::vector<std::string> only;     ///< scenario names to run (empty: all)
  std::uint64_t seed = 7;            ///< the simulated dives' seed (and the kill moment's)
  std::string lcm_url = "udpm://239.255.76.67:7671?ttl=0";
};

struct ScenarioResult {
  std::string name, description;
  bool navd_alive = false;  ///< still running at the end (after its restart for kill_restart)
  int navd_exit_code = -1;  ///< after SIGTERM at the end (0 = clean)
  double detected_after_s = -1.0;
  std::string detected_by;  ///< which field, e.g. "dvl.last_message_age_s = 1.2"
  double max_xy_error_m = 0.0;
  double nees_before = 0.0, nees_during = 0.0, nees_after = 0.0;
  double sigma_xy_start_m = 0.0, sigma_xy_end_m = 0.0;
  int delayed_states_lost = 0;
  double map_xy_rms_m = -1.0;  ///< -1: no bounds snapshot received
  int solutions = 0;           ///< NAVD_SOLUTION messages compared with the truth
  double player_max_late_s = 0.0;
  std::string notes;  ///< what the host fault did / what navd logged about it
  bool pass = false;
  std::string reason;  ///< failed criteria, "; "-separated ("" when pass)
  /// Failed scenario-specific criteria (must_reconnect, no_late_measurements), "; "-separated;
  /// judge() adds them to `reason`.
  std::string scenario_failures;
};

/// Runs the scenarios (options.only, else all of standard_scenarios(short_version)), one at a
/// time, and writes faults.md / faults.json into out_dir. Throws std::runtime_error when the
/// dive cannot be simulated or navd cannot be started (naming what and where).
std::vector<ScenarioResult> run_campaign(const CampaignOptions& options);

/// The campaign table (markdown) and the results as JSON.
std::string campaign_markdown(const std::vector<ScenarioResult>& results);
nlohmann::json campaign_json(const std::vector<ScenarioResult>& results);

}  // namespace nav::campaign
