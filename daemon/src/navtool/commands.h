#pragma once
// navtool subcommands. Each lives in its own cmd_<name>.cpp and adds itself to the CLI11 app
// here; main.cpp calls every add_*_command in turn. A subcommand's callback returns through
// CLI11 (exit code via nav::tool::ExitCode) and prints machine-readable output on stdout only.

#include <CLI/CLI.hpp>

namespace nav::tool {

/// Thrown by a subcommand to end navtool with a message on stderr and a non-zero status.
struct CommandError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// --- registered subcommands (one line per cmd_<name>.cpp) ---

}  // namespace nav::tool
