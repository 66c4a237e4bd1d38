#pragma once
// Test helper: runs the built navtool binary (NAVTOOL_PATH, defined by CMake for the navtool
// tests) through the shell and captures its exit code, stdout and stderr. Included by relative
// path ("support/navtool_run.h") from the tests beside this folder; test-only.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace nav::tool::test {

/// What one navtool run printed and how it ended.
struct NavtoolOutput {
  int exit_code = -1;  ///< exit status; -1 when navtool did not exit normally (signal)
  std::string out;     ///< everything written to stdout
  std::string err;     ///< everything written to stderr
};

/// The whole content of the file at `path` (empty when it cannot be read).
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The lines of `text` without their '\n' (no empty last line for a trailing '\n').
inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// Runs `navtool <args>` (`args` already shell-quoted) with stdout and stderr redirected to files
/// in a per-process temporary directory, which is removed again afterwards.
inline NavtoolOutput run_navtool(const std::string& args) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("navtool_run_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path out = dir / "stdout", err = dir / "stderr";
  const std::string command = std::string("'") + NAVTOOL_PATH + "' " + args + " >'" + out.string() +
                              "' 2>'" + err.string() + "'";
  const int status = std::system(command.c_str());
  NavtoolOutput result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = read_text(out);
  result.err = read_text(err);
  std::error_code ignored;
  fs::remove_all(dir, ignored);
  return result;
}

/// The "summary" object of the `{"summary": ...}` line navtool parse writes to stderr, or a null
/// json when `err` has none.
inline nlohmann::json summary_of(const std::string& err) {
  const auto at = err.find("{\"summary\"");
  if (at == std::string::npos) return nlohmann::json();
  const auto end = err.find('\n', at);
  return nlohmann::json::parse(
      err.substr(at, end == std::string::npos ? end : end - at))["summary"];
}

}  // namespace nav::tool::test
