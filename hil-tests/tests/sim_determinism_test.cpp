// The simulator is deterministic: the same seed gives byte-identical dive files, another seed
// a different dive; navtool simulate writes the same directory as the library call.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "../../daemon/tests/support/navtool_run.h"
#include "support/sim_dive.h"

namespace nav::sim::test {
namespace {

const auto* const kCleanup = ::testing::AddGlobalTestEnvironment(new ScratchCleanup);

SimSummary simulate(const std::filesystem::path& dir, std::uint64_t seed, int images) {
  SimOptions o = sim_options(dir, seed, images);
  return simulate_dive(o, sim_config_path().string());
}

TEST(SimDeterminism, SameSeedGivesByteIdenticalFiles) {
  const auto a = scratch_dir("same_a"), b = scratch_dir("same_b");
  simulate(a, 7, 30);
  simulate(b, 7, 30);
  for (const char* f : {"dive.lcmlog", "truth.csv", "images.csv", "sim.json", "config.yaml"}) {
    const std::string ta = file_text(a / f);
    EXPECT_FALSE(ta.empty()) << f;
    EXPECT_TRUE(ta == file_text(b / f)) << f << " differs between two runs with seed 7";
  }
}

TEST(SimDeterminism, DifferentSeedGivesADifferentDive) {
  const auto a = scratch_dir("seed_a"), b = scratch_dir("seed_b");
  simulate(a, 1, 30);
  simulate(b, 2, 30);
  EXPECT_NE(file_text(a / "dive.lcmlog"), file_text(b / "dive.lcmlog"));
  EXPECT_NE(file_text(a / "truth.csv"), file_text(b / "truth.csv"));
}

TEST(SimDeterminism, NavtoolSimulateWritesTheDiveDirectoryAndPrintsSimJson) {
  const auto dir = scratch_dir("navtool");
  const tool::test::NavtoolOutput r = tool::test::run_navtool(
      "simulate --out '" + dir.string() + "' --images 20 --seed 3 --outlier-rate 0.1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json printed = nlohmann::json::parse(r.out);
  const nlohmann::json file = nlohmann::json::parse(file_text(dir / "sim.json"));
  EXPECT_EQ(printed, file);
  EXPECT_EQ(file["images"], 20);
  EXPECT_EQ(file["options"]["seed"], 3);
  EXPECT_DOUBLE_EQ(file["options"]["outlier_rate"].get<double>(), 0.1);
  EXPECT_EQ(file_text(dir / "config.yaml"), file_text(sim_config_path()));
  // The library call with the same options writes the same log.
  const auto lib = scratch_dir("navtool_lib");
  SimOptions o = sim_options(lib, 3, 20);
  o.oracle.outlier_rate = 0.1;
  simulate_dive(o, sim_config_path().string());
  EXPECT_TRUE(file_text(lib / "dive.lcmlog") == file_text(dir / "dive.lcmlog"));
}

TEST(SimDeterminism, NavtoolSimulateReportsABadConfig) {
  const auto dir = scratch_dir("badcfg");
  const tool::test::NavtoolOutput r =
      tool::test::run_navtool("simulate --out '" + dir.string() + "' --config /nonexistent.yaml");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("/nonexistent.yaml"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace nav::sim::test
