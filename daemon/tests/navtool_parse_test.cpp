// Tests of `navtool parse` (the built navtool binary, NAVTOOL_PATH): one JSON record per line
// on stdout, {"summary": ...} on stderr, non-zero exit for an unknown format or missing file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "nav/testing/data.h"
#include "support/navtool_run.h"

namespace {

using nlohmann::json;

struct RunResult {
  int exit_code = -1;
  std::vector<std::string> stdout_lines;
  std::string stderr_text;
};

/// Runs navtool with `args` (already shell-quoted), capturing stdout lines and stderr.
RunResult run_navtool(const std::string& args) {
  const auto run = nav::tool::test::run_navtool(args);
  return {run.exit_code, nav::tool::test::lines_of(run.out), run.err};
}

json summary_of(const RunResult& r) { return nav::tool::test::summary_of(r.stderr_text); }

TEST(NavtoolParse, Pd0RealRecordingOneLinePerEnsembleAndSummary) {
  NAV_REQUIRE_DATA(path, "dvl/RDI_withBT.000");
  const RunResult r = run_navtool("parse --format pd0 '" + path.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  ASSERT_EQ(r.stdout_lines.size(), 1721u);
  const json summary = summary_of(r);
  ASSERT_TRUE(summary.is_object()) << r.stderr_text;
  EXPECT_EQ(summary["records"], 1721);
  EXPECT_EQ(summary["bytes"], 1000000);
  EXPECT_EQ(summary["checksum_failures"], 0);
  EXPECT_EQ(summary["dropped_bytes"], 99);  // the file ends 99 bytes into ensemble 1722
  EXPECT_EQ(summary["malformed"], 1);       // ... counted as one truncated ensemble

  // Ensemble 1 against RDI_withBT.expected.csv (dolfyn).
  const json first = json::parse(r.stdout_lines[0]);
  EXPECT_EQ(first["ensemble"], 1);
  EXPECT_NEAR(first["time_unix_s"].get<double>(), 1495626613.400, 5e-4);
  EXPECT_NEAR(first["heading_deg"].get<double>(), 195.38, 5e-3);
  EXPECT_NEAR(first["pitch_deg"].get<double>(), 2.92, 5e-3);
  EXPECT_NEAR(first["roll_deg"].get<double>(), -1.28, 5e-3);
  EXPECT_NEAR(first["temperature_c"].get<double>(), 7.29, 5e-3);
  EXPECT_NEAR(first["sound_speed_mps"].get<double>(), 1480.0, 0.5);
  EXPECT_NEAR(first["depth_m"].get<double>(), 0.2, 0.05);
  EXPECT_NEAR(first["pressure_dbar"].get<double>(), 0.255, 5e-4);
  EXPECT_EQ(first["coord_frame"], "earth");
  EXPECT_EQ(first["has_bottom_track"], true);
  ASSERT_EQ(first["bt_velocity_mps"].size(), 4u);
  for (const auto& v : first["bt_velocity_mps"]) EXPECT_TRUE(v.is_null());

  // Ensemble 508, the first with valid bottom track (values read by hand from the file).
  const json e = json::parse(r.stdout_lines[507]);
  EXPECT_EQ(e["ensemble"], 508);
  const double vel[4] = {0.052, 0.062, 0.091, -0.003}, range[4] = {6.86, 10.39, 7.53, 9.05};
  for (int b = 0; b < 4; ++b) {
    EXPECT_NEAR(e["bt_velocity_mps"][b].get<double>(), vel[b], 1e-9);
    EXPECT_NEAR(e["bt_range_m"][b].get<double>(), range[b], 1e-9);
  }
  EXPECT_NEAR(e["heading_deg"].get<double>(), 321.18, 1e-9);
}

TEST(NavtoolParse, Pd6File) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("navtool_parse_pd6_" + std::to_string(::getpid()) + ".txt");
  {
    std::ofstream out(path, std::ios::binary);
    out << "junk:SA, -2.31, +1.07,271.45\r\n:TS,17052412025390,35.0,+21.5,  12.3,1524.5,  0\r\n"
           ":BE,  -100,  +200,   -30,A\r\n:BE,-32768,-32768,-32768,V\r\n";
  }
  const RunResult r = run_navtool("parse --format pd6 '" + path.string() + "'");
  std::filesystem::remove(path);
  ASSERT_EQ(r.exit_code, 0) << r.stderr_text;
  ASSERT_EQ(r.stdout_lines.size(), 4u);
  const json sa = json::parse(r.stdout_lines[0]);
  EXPECT_EQ(sa["type"], "SA");
  EXPECT_NEAR(sa["heading_deg"].get<double>(), 271.45, 1e-9);
  const json be = json::parse(r.stdout_lines[2]);
  EXPECT_EQ(be["type"], "BE");
  EXPECT_NEAR(be["velocity_mps"][1].get<double>(), 0.2, 1e-12);
  EXPECT_NEAR(be["time_unix_s"].get<double>(), 1495627373.9, 1e-6);
  EXPECT_TRUE(json::parse(r.stdout_lines[3])["velocity_mps"][0].is_null());
  const json summary = summary_of(r);
  EXPECT_EQ(summary["records"], 4);
  EXPECT_EQ(summary["dropped_bytes"], 4);
}

TEST(NavtoolParse, UnknownFormatListsTheKnownOnes) {
  const RunResult r = run_navtool("parse --format nosuchformat /dev/null");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.stderr_text.find("nosuchformat"), std::string::npos) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("pd0"), std::string::npos) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("pd6"), std::string::npos) << r.stderr_text;
  EXPECT_TRUE(r.stdout_lines.empty());
}

TEST(NavtoolParse, UnreadableFileIsAnError) {
  const RunResult r = run_navtool("parse --format pd0 /nonexistent/navtool_parse_test.pd0");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.stderr_text.find("/nonexistent/navtool_parse_test.pd0"), std::string::npos)
      << r.stderr_text;
}

}  // namespace
