// The data-file contract of the test support (tests/support/nav/testing/data.h): the real data
// ships in the repository's data/ folder (NAV_DATA_DIR), every file a test reads is there, and
// NAV_REQUIRE_DATA turns a missing file into a fatal test failure that names the path, never
// into a skip.
#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "nav/testing/data.h"

namespace {

constexpr const char* kMissing = "posegraphs/no-such-graph.g2o";

// Calls NAV_REQUIRE_DATA on a file that does not exist; the macro must return from here.
void require_missing_file() {
  NAV_REQUIRE_DATA(path, kMissing);
  ADD_FAILURE() << "NAV_REQUIRE_DATA returned normally for the missing file " << path;
}

}  // namespace

TEST(DataPath, DataPathIsInsideNavDataDir) {
  const std::filesystem::path path = nav::testing::data_path("dvl/RDI_withBT.000");
  EXPECT_EQ(path, std::filesystem::path(NAV_DATA_DIR) / "dvl" / "RDI_withBT.000");
}

TEST(DataPath, MissingFileIsAFatalFailureNamingThePath) {
  EXPECT_FATAL_FAILURE(require_missing_file(), kMissing);
}

TEST(DataPath, MissingFileIsNotASkip) {
  ::testing::TestPartResultArray results;
  {
    ::testing::ScopedFakeTestPartResultReporter reporter(
        ::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &results);
    require_missing_file();
  }
  ASSERT_EQ(results.size(), 1);
  const ::testing::TestPartResult& result = results.GetTestPartResult(0);
  EXPECT_TRUE(result.fatally_failed());
  EXPECT_FALSE(result.skipped());
  EXPECT_NE(std::string(result.message()).find(NAV_DATA_DIR), std::string::npos)
      << result.message();
}

// Every file the test suites read (data/README.md, "used by"), present and not empty.
TEST(DataPath, EveryFileTheTestsReadIsShipped) {
  for (const char* relative :
       {"dvl/RDI_withBT.000", "dvl/RDI_withBT.expected.csv", "dvl/RDI_test01.000",
        "dvl/RDI_test01.expected.csv", "dvl/winriver01.PD0", "posegraphs/tinyGrid3D.g2o",
        "posegraphs/smallGrid3D.g2o", "posegraphs/parking-garage.g2o", "posegraphs/sphere2500.g2o",
        "images/skerki/img_1.tif", "images/sparus/frames.csv", "images/sparus/camera_poses.csv",
        "images/mosaic-scene/scene1.png", "images/mosaic-scene/scene2.png"}) {
    const std::filesystem::path path = nav::testing::data_path(relative);
    ASSERT_TRUE(std::filesystem::is_regular_file(path)) << path << " is missing";
    EXPECT_GT(std::filesystem::file_size(path), 0u) << path << " is empty";
  }
}
