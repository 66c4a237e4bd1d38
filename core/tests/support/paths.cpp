// The build tree's paths for the tests (nav/testing/paths.h). The NAV_PATHS_* definitions are
// set on this file alone by the top CMakeLists.txt, once every executable target exists.
#include "nav/testing/paths.h"

namespace nav::test_paths {

const char* source_dir() { return NAV_PATHS_SOURCE_DIR; }
const char* data_dir() { return NAV_PATHS_DATA_DIR; }
const char* navtool_path() { return NAV_PATHS_NAVTOOL; }
const char* navd_path() { return NAV_PATHS_NAVD; }

}  // namespace nav::test_paths
