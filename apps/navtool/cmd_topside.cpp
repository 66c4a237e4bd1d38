// `navtool topside [--config C] [--lcm-url URL] [--listen ADDR:PORT] [--web-root DIR]`: the
// operators' live
// view of navd. With --config (navd's YAML) it takes the LCM URL and channel names from it and
// shows a health row for every configured sensor. Subscribes (read-only) to navd's LCM channels and serves the bundled web page,
// its WebSocket feed (/ws) and a Foxglove ws-protocol v1 endpoint on one port
// (daemon/include/nav/daemon/topside/). Prints {"url": "http://ADDR:PORT/"} on stdout once
// listening; runs until SIGINT/SIGTERM.
#include <csignal>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/daemon/topside/lcm_bridge.h"
#include "nav/daemon/topside/server.h"
#include "navtool/commands.h"

namespace nav::tool {
namespace {

struct TopsideArgs {
  std::string config_path;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string listen = "127.0.0.1:8765";
  std::string web_root = NAV_TOPSIDE_WEB_ROOT;
  std::size_t queue_capacity = 256;
  bool lcm_url_given = false;
};

void run_topside(const TopsideArgs& args) {
  const auto colon = args.listen.rfind(':');
  if (colon == std::string::npos) {
    throw CommandError("--listen '" + args.listen + "': expected ADDR:PORT, e.g. 127.0.0.1:8765");
  }
  daemon::topside::ServerOptions options;
  options.address = args.listen.substr(0, colon);
  try {
    const int port = std::stoi(args.listen.substr(colon + 1));
    if (port < 0 || port > 65535) throw std::out_of_range("port");
    options.port = static_cast<std::uint16_t>(port);
  } catch (const std::exception&) {
    throw CommandError("--listen '" + args.listen + "': the port must be 0..65535");
  }
  options.web_root = args.web_root;
  options.queue_capacity = args.queue_capacity;
  if (!std::filesystem::exists(options.web_root / "index.html")) {
    throw CommandError("no index.html in --web-root '" + args.web_root +
                       "' (built by the nav_topside_web target)");
  }

  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);  // before any thread starts

  std::string lcm_url = args.lcm_url;
  daemon::topside::BridgeChannels channels;
  nlohmann::json sensors = nlohmann::json::array();
  if (!args.config_path.empty()) {
    daemon::NavdConfig config;
    try {
      config = daemon::load_config_file(args.config_path);
    } catch (const daemon::ConfigError& e) {
      throw CommandError(e.what());
    }
    if (!args.lcm_url_given) lcm_url = config.lcm.url;
    channels = {config.lcm.nav_solution.name, config.lcm.health.name,
                config.lcm.bounds.name,       config.lcm.bounds_snapshot.name,
                config.lcm.camera_links.name, config.lcm.link_proposals.name};
    for (const auto& s : config.sensors) {
      sensors.push_back({{"name", s.name}, {"type", daemon::to_string(s.type)}});
    }
  }
  daemon::topside::TopsideServer server(options);
  server.publish_view("TOPSIDE_CONFIG", {{"sensors", sensors}}, "TOPSIDE_CONFIG");
  try {
    daemon::topside::LcmBridge bridge(lcm_url, channels, server);
    server.start();
    bridge.start();
    const std::string url = "http://" + options.address + ":" + std::to_string(server.port()) + "/";
    std::printf("%s\n", nlohmann::json{{"url", url}}.dump().c_str());
    std::fflush(stdout);
    int signal = 0;
    sigwait(&set, &signal);
    bridge.stop();
    server.stop();
    const auto s = server.stats();
    const auto b = bridge.stats();
    std::fprintf(stderr,
                 "navtool topside: %llu LCM messages (%llu undecodable), %llu frames sent, "
                 "%llu dropped, %llu clients closed for bad input\n",
                 static_cast<unsigned long long>(b.messages),
                 static_cast<unsigned long long>(b.decode_errors),
                 static_cast<unsigned long long>(s.frames_sent),
                 static_cast<unsigned long long>(s.frames_dropped),
                 static_cast<unsigned long long>(s.clients_closed_bad_input));
  } catch (const std::runtime_error& e) {
    throw CommandError(e.what());
  }
}

void add_topside(CLI::App& app) {
  auto args = std::make_shared<TopsideArgs>();
  CLI::App* cmd = app.add_subcommand(
      "topside", "serve navd's LCM channels as a web page, a WebSocket feed and a Foxglove endpoint");
  cmd->add_option("--config", args->config_path, "navd's YAML configuration (URL, channels, sensors)");
  CLI::Option* url = cmd->add_option("--lcm-url", args->lcm_url, "LCM provider URL (overrides lcm.url)")
      ->capture_default_str();
  cmd->add_option("--listen", args->listen, "ADDR:PORT to serve on (port 0: any free port)")
      ->capture_default_str();
  cmd->add_option("--web-root", args->web_root, "folder of the bundled page")->capture_default_str();
  cmd->add_option("--queue", args->queue_capacity, "frames queued per client before the oldest drop")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->callback([args, url] {
    args->lcm_url_given = url->count() > 0;
    run_topside(*args);
  });
}

const CommandRegistration kRegister{"topside", add_topside};

}  // namespace
}  // namespace nav::tool
