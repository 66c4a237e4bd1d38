// navtool: offline companion of navd (survey, simulate, replay, report, covariance, parse,
// sensors, hil-play, demo).
// Each subcommand registers itself from its own cmd_<name>.cpp; see commands.h.
#include <cstdio>

#include "nav/daemon/system/realtime.h"
#include "navtool/commands.h"

namespace nav::tool {
std::map<std::string, AddCommandFn>& command_registry() {
  static std::map<std::string, AddCommandFn> registry;
  return registry;
}
}  // namespace nav::tool

int main(int argc, char** argv) {
  nav::daemon::keep_freed_memory();  // replays: no page faults for buffers allocated again
  CLI::App app{"navtool: offline tools for the navd navigation daemon"};
  app.require_subcommand(1);
  for (const auto& [name, add] : nav::tool::command_registry()) add(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const nav::tool::CommandError& e) {
    std::fprintf(stderr, "navtool: %s\n", e.what());
    return e.exit_status;
  } catch (const nav::tool::CommandExit& e) {
    return e.exit_status;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "navtool: unexpected error: %s\n", e.what());
    return 2;
  }
  return 0;
}
