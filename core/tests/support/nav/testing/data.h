#pragma once
// Locating the real recordings and benchmarks in the repository's data/ folder (CMake cache
// variable NAV_DATA_DIR, default ${CMAKE_SOURCE_DIR}/data; data/README.md lists every file,
// its source and licence). The data ships with the repository, so a missing file is a broken
// checkout or a wrong NAV_DATA_DIR: NAV_REQUIRE_DATA fails the test and prints the path.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "nav/testing/paths.h"

namespace nav::testing {

/// Absolute path of `relative` (e.g. "dvl/RDI_withBT.000") inside the data folder; the file
/// may not exist (NAV_REQUIRE_DATA checks).
inline std::filesystem::path data_path(const std::string& relative) {
  return std::filesystem::path(NAV_DATA_DIR) / relative;
}

}  // namespace nav::testing

/// Declares `var` as the path of `relative` in the data folder. When the file is missing the
/// test fails (fatal failure: the enclosing void test body returns) with the path and the
/// NAV_DATA_DIR it was looked up in.
#define NAV_REQUIRE_DATA(var, relative)                                                 \
  const std::filesystem::path var = ::nav::testing::data_path(relative);                \
  if (!std::filesystem::is_regular_file(var)) {                                         \
    GTEST_FAIL() << "data file " << var << " is missing (NAV_DATA_DIR=" << NAV_DATA_DIR \
                 << "; the repository's data/ folder, see data/README.md)";             \
  }
