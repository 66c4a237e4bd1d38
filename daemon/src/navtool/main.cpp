// navtool: offline companion of navd (simulate, replay, covariance, parse, register, report).
// Each subcommand is registered from its own file; see commands.h.
#include <spdlog/spdlog.h>

#include <cstdio>

#include "navtool/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"navtool: offline tools for the navd navigation daemon"};
  app.require_subcommand(1);
  // --- subcommand registration (keep in the order of commands.h) ---

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const nav::tool::CommandError& e) {
    std::fprintf(stderr, "navtool: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "navtool: unexpected error: %s\n", e.what());
    return 2;
  }
  return 0;
}
