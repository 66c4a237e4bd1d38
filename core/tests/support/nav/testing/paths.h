#pragma once
// Where a test finds the checkout, the data folder and the built executables. The paths are
// compiled into one source file (core/tests/support/paths.cpp, its definitions set by the top
// CMakeLists.txt) instead of onto every test's command line: an absolute path there would make
// each test object differ between two checkouts of the same commit, so a compiler cache could
// not share them (a fresh clone in CI would rebuild every test). nav_add_tests force-includes
// this header into every test; the macros expand to const char* expressions.

namespace nav::test_paths {

const char* source_dir();    ///< the checkout (CMAKE_SOURCE_DIR)
const char* data_dir();      ///< the data folder (CMake cache variable NAV_DATA_DIR)
const char* navtool_path();  ///< the built navtool; "" in a build without it
const char* navd_path();     ///< the built navd; "" in a build without it

}  // namespace nav::test_paths

#define NAV_SOURCE_DIR (::nav::test_paths::source_dir())
#define NAV_DATA_DIR (::nav::test_paths::data_dir())
#define NAVTOOL_PATH (::nav::test_paths::navtool_path())
#define NAVD_PATH (::nav::test_paths::navd_path())
