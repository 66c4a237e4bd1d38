// `navtool parse` with the ASCII formats (nmea, kvh, paro, altimeter): small files written to a
// temporary directory, records as JSON lines on stdout, the summary on stderr.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/navtool_run.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct ParseRun {
  int status = -1;
  std::vector<json> records;
  json summary;
};

fs::path temp_dir() {
  const fs::path dir =
      fs::temp_directory_path() / ("navtool_parse_ascii_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

fs::path write_file(const std::string& name, const std::string& bytes) {
  const fs::path path = temp_dir() / name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

ParseRun navtool_parse(const std::string& format, const fs::path& file) {
  const auto output =
      nav::tool::test::run_navtool("parse --format " + format + " '" + file.string() + "'");
  ParseRun run;
  run.status = output.exit_code;
  for (const std::string& line : nav::tool::test::lines_of(output.out)) {
    if (!line.empty()) run.records.push_back(json::parse(line));
  }
  run.summary = nav::tool::test::summary_of(output.err);
  return run;
}

/// Removes the temporary directory after the last test.
class TempDirCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(temp_dir(), ignored);
  }
};
const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new TempDirCleanup);

TEST(NavtoolParseAscii, NmeaRecordsInDegreesAndSummary) {
  const auto file = write_file("t.nmea",
                               "$HEHDT,41.87,T*25\r\nnoise\r\n$PIXSE,ATITUD,-0.729,-15.705*58\r\n"
                               "$PIXSE,POSITI,39.27301545,14.38044597,*4D\r\n"
                               "$HEHDT,41.87,T*26\r\n$PIXSE,TIME__,085832.738582*6B\r\n");
  const ParseRun run = navtool_parse("nmea", file);
  EXPECT_EQ(run.status, 0);
  ASSERT_EQ(run.records.size(), 2u);
  EXPECT_EQ(run.records[0]["sentence"], "HDT");
  EXPECT_DOUBLE_EQ(run.records[0]["heading_deg"].get<double>(), 41.87);
  EXPECT_DOUBLE_EQ(run.records[1]["roll_deg"].get<double>(), -0.729);
  EXPECT_DOUBLE_EQ(run.records[1]["pitch_deg"].get<double>(), 15.705);
  ASSERT_TRUE(run.summary.is_object());
  EXPECT_EQ(run.summary["records"], 2);
  EXPECT_EQ(run.summary["checksum_failures"], 2);  // POSITI (altitude removed) and 2nd HDT
  EXPECT_EQ(run.summary["unsupported"], 1);
  EXPECT_GT(run.summary["dropped_bytes"].get<int>(), 0);
}

TEST(NavtoolParseAscii, KvhParoAltimeter) {
  const ParseRun kvh = navtool_parse("kvh", write_file("t.kvh", "   1.2500000   1\r\n  0.5 0\r\n"));
  EXPECT_EQ(kvh.status, 0);
  ASSERT_EQ(kvh.records.size(), 2u);
  EXPECT_DOUBLE_EQ(kvh.records[0]["rate_deg_per_s"].get<double>(), 1.25);
  EXPECT_TRUE(kvh.records[1]["rate_deg_per_s"].is_null());
  EXPECT_EQ(kvh.records[1]["sensor_valid"], false);

  const ParseRun paro = navtool_parse("paro", write_file("t.paro", "*000114.6959\r\n*0100P3\r\n"));
  EXPECT_EQ(paro.status, 0);
  ASSERT_EQ(paro.records.size(), 1u);
  EXPECT_NEAR(paro.records[0]["pressure_pa"].get<double>(), 101325.0, 1.0);
  EXPECT_EQ(paro.summary["unsupported"], 1);

  const ParseRun alt =
      navtool_parse("altimeter", write_file("t.alt", "012.34m\r\n099.99m\r\n900.00m\r\n"));
  EXPECT_EQ(alt.status, 0);
  ASSERT_EQ(alt.records.size(), 3u);
  EXPECT_DOUBLE_EQ(alt.records[0]["range_m"].get<double>(), 12.34);
  EXPECT_EQ(alt.records[1]["status"], "no_echo");
  EXPECT_TRUE(alt.records[1]["range_m"].is_null());
  EXPECT_EQ(alt.records[2]["status"], "out_of_range");
  EXPECT_EQ(alt.summary["out_of_range"], 1);
}

TEST(NavtoolParseAscii, UnreadableFileFails) {
  const ParseRun run = navtool_parse("nmea", temp_dir() / "does_not_exist.nmea");
  EXPECT_NE(run.status, 0);
  EXPECT_TRUE(run.records.empty());
}

}  // namespace
