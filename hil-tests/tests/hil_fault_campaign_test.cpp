// The fault campaign's short version (docs/faults.md, `navtool fault-campaign --short`), ~2.5
// min: a 43-s simulated dive played at real time to the real navd three times, with the DVL
// silent for 15 s, depth spikes of +-10 m for 10 s, the heading's pty closed for 10 s.
// Asserted: navd rides through each (running at the end, exit 0 on SIGTERM), its health
// reports each fault within 3 s by the expected field, the published XY uncertainty grows
// while the DVL is silent, the heading comes back (reconnects), solutions and the map are
// heard, and faults.md / faults.json hold the three rows. The NEES columns are printed, not
// asserted: docs/faults.md records them (the published covariance is the last image's between
// images).
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "nav/campaign/fault_campaign.h"
#include "support/sim_dive.h"

namespace {

TEST(FaultCampaign, ShortCampaignDetectsEachFaultWithin3sAndNavdRidesThrough) {
  const auto dir = nav::sim::test::scratch_dir("fault_campaign");
  nav::campaign::CampaignOptions o;
  o.out_dir = dir;
  o.navd_path = NAVD_PATH;
  o.sim_config = nav::sim::test::sim_config_path();
  o.short_version = true;
  const std::vector<nav::campaign::ScenarioResult> results = nav::campaign::run_campaign(o);
  std::printf("%s", nav::campaign::campaign_markdown(results).c_str());
  ASSERT_EQ(results.size(), 3u);
  for (const nav::campaign::ScenarioResult& r : results) {
    EXPECT_TRUE(r.navd_alive) << r.name;
    EXPECT_EQ(r.navd_exit_code, 0) << r.name;
    EXPECT_GE(r.detected_after_s, 0.0) << r.name << ": not reported in health";
    EXPECT_LE(r.detected_after_s, 3.0) << r.name << " " << r.detected_by;
    EXPECT_GT(r.solutions, 100) << r.name;
    EXPECT_LT(r.max_xy_error_m, 20.0) << r.name;
  }
  EXPECT_EQ(results[0].detected_by.rfind("dvl.", 0), 0u) << results[0].detected_by;
  EXPECT_GT(results[0].sigma_xy_end_m, results[0].sigma_xy_start_m);  // dead reckoning
  EXPECT_EQ(results[1].detected_by.rfind("depth.", 0), 0u) << results[1].detected_by;
  EXPECT_EQ(results[2].detected_by, "heading.connected = false");
  // The heading came back after the window: its health shows a reconnect.
  std::ifstream health(dir / "scenarios" / results[2].name / "health.csv");
  std::string header, line, last;
  std::getline(health, header);
  while (std::getline(health, line)) last = line;
  const std::size_t column = std::count(
      header.begin(), header.begin() + static_cast<long>(header.find("heading.reconnects")), ',');
  std::stringstream cells(last);
  std::string cell;
  for (std::size_t i = 0; i <= column; ++i) std::getline(cells, cell, ',');
  EXPECT_EQ(cell, "1") << header << "\n" << last;

  std::ifstream json_in(dir / "faults.json");
  const nlohmann::json json = nlohmann::json::parse(json_in);
  ASSERT_EQ(json.size(), 3u);
  EXPECT_EQ(json[0]["name"], "dvl_dropout_15s");
  std::ifstream md(dir / "faults.md");
  std::string table((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(table.find("heading_unplug_10s"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
