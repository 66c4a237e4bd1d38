#pragma once
// Locating the real recordings in ../shared/data (CMake cache variable NAV_DATA_DIR).
// Tests call NAV_REQUIRE_DATA(path) and are skipped, with the reason printed, when the data
// folder is absent (e.g. a checkout without ../shared beside it).

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace nav::testing {

/// Absolute path of `relative` inside the shared data folder (may not exist).
inline std::filesystem::path data_path(const std::string& relative) {
  return std::filesystem::path(NAV_DATA_DIR) / relative;
}

}  // namespace nav::testing

/// Declares `var` as the path of `relative` in the data folder, or skips the test.
#define NAV_REQUIRE_DATA(var, relative)                                                   \
  const std::filesystem::path var = ::nav::testing::data_path(relative);                  \
  if (!std::filesystem::exists(var)) {                                                    \
    GTEST_SKIP() << "shared data file " << var                                            \
                 << " is absent (set -DNAV_DATA_DIR=<path to shared/data>); test skipped"; \
  }
