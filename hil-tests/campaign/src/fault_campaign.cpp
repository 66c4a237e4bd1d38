// The fault campaign: dives, scenarios one at a time, verdicts, the table; see
// fault_campaign.h.
#include "nav/campaign/fault_campaign.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <stdexcept>

#include "campaign_dive.h"
#include "host_faults.h"
#include "scenario_run.h"

namespace nav::campaign {
namespace fs = std::filesystem;
namespace {

constexpr double kDetectWithinS = 3.0;
constexpr double kNeesBound = 6.0;  ///< 95 % of chi-square, 2 DOF (5.99)

/// The dive of `images` images in out_dir/dives (simulated once, then reused).
fs::path dive_for(const CampaignOptions& o, int images) {
  return simulated_dive(o.out_dir / "dives" / ("dive_" + std::to_string(images)), images, o.seed,
                        o.sim_config, false);
}

std::string fmt(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

/// A window's mean NEES, "-" for a window without solutions (-1).
std::string nees(double value) { return value < 0.0 ? "-" : fmt("%.2f", value); }

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  if (!out) throw std::runtime_error(path.string() + ": cannot write");
}

}  // namespace

void judge(const FaultScenario& scenario, ScenarioResult& r) {
  std::string why;
  auto fail = [&](const std::string& what) { why += (why.empty() ? "" : "; ") + what; };
  if (!r.navd_alive) fail("navd not running at the end");
  if (r.navd_alive && r.navd_exit_code != 0) fail("navd exit " + std::to_string(r.navd_exit_code));
  if (scenario.detector != Detector::kNone &&
      (r.detected_after_s < 0.0 || r.detected_after_s > kDetectWithinS)) {
    fail(r.detected_after_s < 0.0 ? "not reported in health"
                                  : "reported after " + fmt("%.1f", r.detected_after_s) + " s");
  }
  if (r.solutions == 0) fail("no solution heard");
  if (r.nees_during < 0.0) fail("no solution during the fault");
  if (r.nees_after < 0.0) fail("no solution after the fault");
  if (!(r.nees_during <= kNeesBound)) fail("NEES during " + fmt("%.1f", r.nees_during));
  if (!(r.nees_after <= kNeesBound)) fail("NEES after " + fmt("%.1f", r.nees_after));
  if (scenario.uncertainty_must_grow && !(r.sigma_xy_end_m > r.sigma_xy_start_m)) {
    fail("XY sigma did not grow (" + fmt("%.3f", r.sigma_xy_start_m) + " -> " +
         fmt("%.3f", r.sigma_xy_end_m) + " m)");
  }
  if (r.delayed_states_lost > 0) {
    fail(std::to_string(r.delayed_states_lost) + " delayed states lost");
  }
  if (!r.scenario_failures.empty()) fail(r.scenario_failures);
  r.pass = why.empty();
  r.reason = why;
}

std::vector<ScenarioResult> run_campaign(const CampaignOptions& o) {
  fs::create_directories(o.out_dir);
  const std::string netns = enter_private_namespaces();
  if (!netns.empty())
    std::fprintf(stderr, "fault campaign: no private namespaces (%s)\n", netns.c_str());
  std::vector<ScenarioResult> results;
  for (const FaultScenario& s : standard_scenarios(o.short_version)) {
    if (!o.only.empty() && std::find(o.only.begin(), o.only.end(), s.name) == o.only.end()) {
      continue;
    }
    ScenarioSetup setup;
    setup.out_dir = o.out_dir;
    setup.dive_dir = dive_for(o, dive_images(o.short_version, s.long_dive));
    setup.navd_path = o.navd_path;
    setup.lcm_url = o.lcm_url;
    setup.camera = netns.empty();
    setup.seed = o.seed;
    std::fprintf(stderr, "fault campaign: %s (%s) ...\n", s.name.c_str(), s.description.c_str());
    results.push_back(run_scenario(s, setup));
    const ScenarioResult& r = results.back();
    std::fprintf(stderr, "fault campaign: %s %s %s\n", s.name.c_str(), r.pass ? "PASS" : "FAIL",
                 r.reason.c_str());
  }
  write_text(o.out_dir / "faults.md", campaign_markdown(results));
  write_text(o.out_dir / "faults.json", campaign_json(results).dump(2) + "\n");
  return results;
}

std::string campaign_markdown(const std::vector<ScenarioResult>& results) {
  std::string md =
      "| fault | detected after (s), by | max XY error (m) | NEES before / during / after | "
      "XY sigma start -> end (m) | map XY RMS (m) | delayed states lost | navd | verdict |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  for (const ScenarioResult& r : results) {
    const std::string detected =
        r.detected_after_s < 0.0 ? "-"
                                 : fmt("%.1f", r.detected_after_s) + ", `" + r.detected_by + "`";
    md += "| " + r.name + ": " + r.description + " | " + detected + " | " +
          fmt("%.3f", r.max_xy_error_m) + " | " + nees(r.nees_before) + " / " +
          nees(r.nees_during) + " / " + nees(r.nees_after) + " | " +
          fmt("%.3f", r.sigma_xy_start_m) + " -> " + fmt("%.3f", r.sigma_xy_end_m) + " | " +
          (r.map_xy_rms_m < 0.0 ? std::string("-") : fmt("%.3f", r.map_xy_rms_m)) + " | " +
          std::to_string(r.delayed_states_lost) + " | " +
          (r.navd_alive ? "running, exit " + std::to_string(r.navd_exit_code) : "gone") + " | " +
          (r.pass ? "pass" : "FAIL: " + r.reason) + (r.notes.empty() ? "" : " (" + r.notes + ")") +
          " |\n";
  }
  return md;
}

nlohmann::json campaign_json(const std::vector<ScenarioResult>& results) {
  nlohmann::json all = nlohmann::json::array();
  for (const ScenarioResult& r : results) {
    all.push_back({{"name", r.name},
                   {"description", r.description},
                   {"navd_alive", r.navd_alive},
                   {"navd_exit_code", r.navd_exit_code},
                   {"detected_after_s", r.detected_after_s},
                   {"detected_by", r.detected_by},
                   {"max_xy_error_m", r.max_xy_error_m},
                   {"nees_before", r.nees_before},
                   {"nees_during", r.nees_during},
                   {"nees_after", r.nees_after},
                   {"sigma_xy_start_m", r.sigma_xy_start_m},
                   {"sigma_xy_end_m", r.sigma_xy_end_m},
                   {"delayed_states_lost", r.delayed_states_lost},
                   {"map_xy_rms_m", r.map_xy_rms_m},
                   {"solutions", r.solutions},
                   {"player_max_late_s", r.player_max_late_s},
                   {"notes", r.notes},
                   {"pass", r.pass},
                   {"reason", r.reason}});
  }
  return all;
}

}  // namespace nav::campaign
