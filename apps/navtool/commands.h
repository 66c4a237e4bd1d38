#pragma once
// navtool subcommands. Each lives in its own cmd_<name>.cpp and registers itself with a
// file-scope `const CommandRegistration kRegister{"name", add_fn};`, so adding a subcommand
// never edits a shared file. main.cpp adds every registered command, sorted by name.
// A subcommand prints machine-readable output on stdout only; messages go to stderr.

#include <CLI/CLI.hpp>

#include <functional>
#include <map>
#include <stdexcept>
#include <string>

namespace nav::tool {

/// Thrown by a subcommand to end navtool with a message on stderr and `exit_status` (1: the
/// command failed; 2: bad options or configuration, where a subcommand distinguishes them).
struct CommandError : std::runtime_error {
  explicit CommandError(const std::string& what, int status = 1)
      : std::runtime_error(what), exit_status(status) {}
  int exit_status;
};

/// Thrown by a subcommand that ends early with this exit status after reporting on its own
/// (`navtool survey`: 1 when the replay failed, its summary already printed).
struct CommandExit {
  int exit_status;
};

/// Adds one subcommand (and its callback) to the application.
using AddCommandFn = std::function<void(CLI::App& app)>;

/// All registered subcommands by name (filled before main() by CommandRegistration objects).
std::map<std::string, AddCommandFn>& command_registry();

struct CommandRegistration {
  CommandRegistration(const std::string& name, AddCommandFn add) {
    command_registry().emplace(name, std::move(add));
  }
};

/// --time-of-use-every K and --time-of-use-markov-blanket of `navtool replay` and `navtool
/// survey` (daemon ReplayOptions::time_of_use_*; defined in cmd_replay.cpp).
void add_time_of_use_options(CLI::App& cmd, int& every_images, bool& markov_blanket);

}  // namespace nav::tool
