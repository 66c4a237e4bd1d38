// navtool parse: decodes a recorded sensor byte stream with one of the drivers' codecs and
// prints one JSON object per decoded record per line on stdout, then the decoder's counters as
// {"summary": {...}} on stderr. Formats register themselves (parse_formats.h); this file owns
// the registry and the subcommand. Exit status 1 for an unknown format or an unreadable file.
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "navtool/commands.h"
#include "navtool/parse/parse_formats.h"

namespace nav::tool {

std::map<std::string, ParseFormat>& parse_format_registry() {
  static std::map<std::string, ParseFormat> registry;
  return registry;
}

namespace {

std::string known_format_names() {
  std::string names;
  for (const auto& [name, format] : parse_format_registry()) {
    if (!names.empty()) names += ", ";
    names += name;
  }
  return names.empty() ? std::string("(none registered)") : names;
}

std::string format_help() {
  std::ostringstream help;
  help << "record format, one of:";
  for (const auto& [name, format] : parse_format_registry()) {
    help << "\n  " << name << ": " << format.help;
  }
  return help.str();
}

struct ParseArgs {
  std::string format;
  std::string file;
  ParseOptions options;
};

void run_parse(const ParseArgs& args) {
  const auto& registry = parse_format_registry();
  const auto it = registry.find(args.format);
  if (it == registry.end()) {
    throw CommandError("parse: unknown format '" + args.format +
                       "'; known formats: " + known_format_names());
  }
  std::ifstream in(args.file, std::ios::binary);
  if (!in) throw CommandError("parse: cannot open '" + args.file + "' for reading");
  nav::drivers::DecodeStats stats;
  it->second.run(in, std::cout, stats, args.options);
  std::cout.flush();
  if (in.bad()) throw CommandError("parse: read error in '" + args.file + "'");
  std::cerr << "{\"summary\": " << stats.to_json() << "}" << std::endl;
}

void add_parse(CLI::App& app) {
  auto args = std::make_shared<ParseArgs>();
  CLI::App* cmd =
      app.add_subcommand("parse",
                         "Decode a recorded sensor stream: one JSON record per line on stdout, "
                         "{\"summary\": counters} on stderr");
  cmd->add_option("--format", args->format, format_help())->required();
  cmd->add_option("file", args->file, "recorded byte stream")->required();
  cmd->add_option("--can-config", args->options.can_config_path,
                  "CAN signal definitions (format can only)");
  cmd->callback([args] { run_parse(*args); });
}

const CommandRegistration kRegister{"parse", add_parse};

}  // namespace
}  // namespace nav::tool
