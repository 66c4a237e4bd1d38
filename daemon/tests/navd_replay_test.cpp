// navd --replay end to end: a small simulated dive (navtool simulate) replayed by navd as fast
// as possible gives exit 0, the replay JSON summary on stdout and the same replay output as
// `navtool replay` (one NavFilter code path).
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "support/navtool_run.h"

namespace nav::tool::test {
namespace {

namespace fs = std::filesystem;

TEST(NavdReplay, PublishesAndMatchesNavtoolReplay) {
  const fs::path root = fs::temp_directory_path() / ("navd_replay_" + std::to_string(::getpid()));
  fs::create_directories(root);
  const std::string dive = (root / "dive").string();
  ASSERT_EQ(run_navtool("simulate --out '" + dive + "' --images 20 --seed 5").exit_code, 0);
  const NavtoolOutput tool =
      run_navtool("replay '" + dive + "' --as-fast-as-possible --out '" + (root / "tool").string() + "'");
  ASSERT_EQ(tool.exit_code, 0) << tool.err;
  const std::string command = std::string("'") + NAVD_PATH + "' --config '" + dive +
                              "/config.yaml' --lcm-url memq:// --replay '" + dive +
                              "/dive.lcmlog' --as-fast-as-possible --out '" +
                              (root / "navd").string() + "' > '" + (root / "out.json").string() +
                              "' 2> '" + (root / "err.txt").string() + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << read_text(root / "err.txt");
  const nlohmann::json s = nlohmann::json::parse(read_text(root / "out.json"));
  EXPECT_EQ(s["images"], 20);
  EXPECT_EQ(s["error"], "");
  EXPECT_DOUBLE_EQ(s["conservative_fraction"].get<double>(), 1.0);
  for (const char* file : {"states.csv", "links.csv", "trajectory.csv"}) {
    EXPECT_EQ(read_text(root / "navd" / file), read_text(root / "tool" / file)) << file;
  }
  std::error_code ignored;
  fs::remove_all(root, ignored);
}

}  // namespace
}  // namespace nav::tool::test
