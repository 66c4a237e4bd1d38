# Helpers shared by every folder: warnings, sanitizers, test and benchmark registration.

# Compile options for project code only (third-party headers come in as SYSTEM includes).
add_library(nav_project_options INTERFACE)
target_compile_options(nav_project_options INTERFACE -Wall -Wextra -Werror)
if(NAV_SANITIZE)
  target_compile_options(nav_project_options INTERFACE
    -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
    # GCC 12 reports false "may be used uninitialized" inside Eigen's evaluators when the
    # sanitizers are on at -O1; the Release build keeps the warning as an error.
    $<$<CXX_COMPILER_ID:GNU>:-Wno-maybe-uninitialized>)
  target_link_options(nav_project_options INTERFACE -fsanitize=address,undefined)
endif()

# nav_add_tests(LIBRARY <target> PREFIX <prefix> [LABEL <label>] [LINK <targets...>]
#               [DEFINITIONS <compile definitions...>] [DEPENDS <targets built first...>])
# Every tests/*_test.cpp beside the calling CMakeLists.txt becomes one GoogleTest executable
# named <folder>_<file stem>, linked to LIBRARY and the shared test support, and registered
# with CTest test by test. A GTEST_SKIP() is reported by ctest as "Skipped" with its reason.
function(nav_add_tests)
  cmake_parse_arguments(ARG "" "LIBRARY;LABEL;PREFIX" "LINK;DEFINITIONS;DEPENDS" ${ARGN})
  if(NOT NAV_BUILD_TESTS)
    return()
  endif()
  file(GLOB_RECURSE test_sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/tests/*_test.cpp)
  foreach(source IN LISTS test_sources)
    get_filename_component(stem ${source} NAME_WE)
    set(test_target ${ARG_PREFIX}_${stem})
    add_executable(${test_target} ${source})
    target_link_libraries(${test_target} PRIVATE ${ARG_LIBRARY} nav_test_support ${ARG_LINK}
                                                 GTest::gtest GTest::gmock GTest::gtest_main)
    # NAV_SOURCE_DIR, NAV_DATA_DIR, NAVTOOL_PATH, NAVD_PATH: functions of the test support
    # (nav/testing/paths.h), not definitions, so the objects do not depend on the checkout's path.
    target_compile_options(${test_target} PRIVATE
      -include ${PROJECT_SOURCE_DIR}/core/tests/support/nav/testing/paths.h)
    if(ARG_DEFINITIONS)
      target_compile_definitions(${test_target} PRIVATE ${ARG_DEFINITIONS})
    endif()
    if(ARG_DEPENDS)
      add_dependencies(${test_target} ${ARG_DEPENDS})
    endif()
    set_target_properties(${test_target} PROPERTIES RUNTIME_OUTPUT_DIRECTORY
                                                    ${CMAKE_BINARY_DIR}/tests)
    gtest_discover_tests(${test_target}
      DISCOVERY_MODE PRE_TEST
      DISCOVERY_TIMEOUT 60
      WORKING_DIRECTORY ${CMAKE_SOURCE_DIR}
      PROPERTIES LABELS "${ARG_LABEL}" TIMEOUT 900)
  endforeach()
endfunction()
