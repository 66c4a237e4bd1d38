// navtool hil-play: hardware-in-the-loop playback of a dive (hil-tests/README.md "Playing a
// dive back"): the sensors' recorded bytes go, at their recorded times, into one
// pseudo-terminal per serial sensor (a stable symlink each) and onto SocketCAN for CAN
// sensors, the dive's images (its rendered frames, or a test pattern) from Aravis' fake GigE
// camera on lo at the dive's image times, and a navd config pointing at them is written, so
// that navd runs in live mode on the played dive in another terminal. Library: hil-tests/player
// (nav::hil::DivePlayer).
// --json prints the playback report on stdout at the end; messages go to stderr.
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "nav/daemon/config/config.h"
#include "nav/hil/dive_player.h"
#include "navtool/commands.h"

namespace nav::tool {
namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) { g_stop.store(true); }

struct HilPlayArgs {
  std::string dive;
  double speed = 1.0;
  std::string serial_dir;
  std::string can_interface = "vcan0";
  std::string config_out;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  bool play_registrations = false;
  bool no_wait = false;
  bool no_camera = false;
  std::string camera_image_dir;
  bool hold = false;
  double reader_timeout_s = 0.0;
  bool json = false;
};

const char* output_name(hil::SensorOutput output) {
  switch (output) {
    case hil::SensorOutput::kPty:
      return "pty";
    case hil::SensorOutput::kCan:
      return "can";
    case hil::SensorOutput::kGige:
      return "gige";
    case hil::SensorOutput::kNotPlayed:
      break;
  }
  return "not_played";
}

nlohmann::json report_json(const hil::PlayReport& r) {
  nlohmann::json sensors = nlohmann::json::array();
  for (const hil::PlayedSensor& s : r.sensors) {
    sensors.push_back({{"name", s.name},
                       {"type", s.type},
                       {"output", output_name(s.output)},
                       {"device", s.device.string()},
                       {"note", s.note},
                       {"messages", s.messages},
                       {"bytes", s.bytes},
                       {"dropped_bytes", s.dropped_bytes},
                       {"dropped_frames", s.dropped_frames}});
  }
  return {{"sensors", sensors},
          {"started", r.started},
          {"stopped", r.stopped},
          {"dive_span_s", r.dive_span_s},
          {"wall_s", r.wall_s},
          {"max_late_s", r.max_late_s},
          {"late_writes", r.late_writes},
          {"dive_start_us", r.dive_start_us},
          {"host_start_us", r.host_start_us},
          {"images_not_played", r.images_not_played},
          {"camera",
           {{"images", r.camera.images},
            {"with_frame", r.camera.with_frame},
            {"frame_missing", r.camera.frame_missing},
            {"sent", r.camera.sent},
            {"not_taken", r.camera.not_taken},
            {"max_send_late_s", r.camera.max_send_late_s},
            {"mean_send_late_s", r.camera.mean_send_late_s}}},
          {"registrations_not_played", r.registrations_not_played},
          {"registrations_played", r.registrations_played},
          {"raw_unknown_sensor", r.raw_unknown_sensor}};
}

void print_plan(const hil::DivePlayer& player, const std::string& config_path, double speed) {
  for (const hil::PlayedSensor& s : player.sensors()) {
    if (s.output == hil::SensorOutput::kNotPlayed) {
      std::fprintf(stderr, "  %s (%s): %s\n", s.name.c_str(), s.type.c_str(), s.note.c_str());
    } else {
      std::fprintf(stderr, "  %s (%s): %s %s%s%s\n", s.name.c_str(), s.type.c_str(),
                   output_name(s.output), s.device.c_str(), s.note.empty() ? "" : ": ",
                   s.note.c_str());
    }
  }
  std::fprintf(stderr, "navd config: %s\n  run: navd --config %s\n", config_path.c_str(),
               config_path.c_str());
  if (speed != 1.0) {
    std::fprintf(stderr,
                 "warning: --speed %g: navd stamps bytes with the host clock, so it sees the dive "
                 "%g times %s (decoding and health are meaningful, the pose is not)\n",
                 speed, speed > 1.0 ? speed : 1.0 / speed, speed > 1.0 ? "shorter" : "longer");
  }
}

void run_hil_play(const HilPlayArgs& args) {
  hil::PlayerOptions o;
  o.speed = args.speed;
  o.serial_dir = args.serial_dir;
  o.can_interface = args.can_interface;
  o.wait_for_readers = !args.no_wait;
  o.fake_gige_camera = !args.no_camera;
  if (args.play_registrations) o.registration_lcm_url = args.lcm_url;
  o.camera_image_dir = args.camera_image_dir;
  o.reader_timeout = std::chrono::milliseconds(static_cast<long>(args.reader_timeout_s * 1e3));
  std::unique_ptr<hil::DivePlayer> player;
  std::string config_path = args.config_out;
  try {
    player = std::make_unique<hil::DivePlayer>(args.dive, o);
    if (config_path.empty()) config_path = (player->serial_dir() / "navd-hil.yaml").string();
    player->write_navd_config(config_path, args.lcm_url);
  } catch (const std::exception& e) {
    throw CommandError(std::string("hil-play: ") + e.what());
  }
  print_plan(*player, config_path, args.speed);
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  if (o.wait_for_readers) std::fprintf(stderr, "waiting for navd to open every pty ...\n");
  hil::PlayReport report;
  try {
    report = player->play(g_stop);
  } catch (const std::exception& e) {
    throw CommandError(std::string("hil-play: ") + e.what());
  }
  std::fprintf(stderr,
               "hil-play: %s: %.1f s of dive in %.1f s, worst lateness %.1f ms, %lld writes "
               "> 10 ms late%s\n",
               player->log_path().c_str(), report.dive_span_s, report.wall_s,
               report.max_late_s * 1e3, static_cast<long long>(report.late_writes),
               report.stopped ? " (stopped)" : "");
  if (report.camera.images > 0) {
    std::fprintf(stderr,
                 "hil-play: camera: %lld images triggered (%lld with the dive's frame, %lld "
                 "missing), %lld sent, worst send %.1f ms after its time\n",
                 static_cast<long long>(report.camera.images),
                 static_cast<long long>(report.camera.with_frame),
                 static_cast<long long>(report.camera.frame_missing),
                 static_cast<long long>(report.camera.sent), report.camera.max_send_late_s * 1e3);
  }
  if (args.hold && report.started && !report.stopped) {
    std::fprintf(stderr, "holding the devices open until Ctrl-C / SIGTERM\n");
    while (!g_stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (args.json) std::cout << report_json(report).dump() << std::endl;
  if (!report.started && !report.stopped) {
    throw CommandError("hil-play: no reader opened every pty within --reader-timeout-s");
  }
}

void add_hil_play(CLI::App& app) {
  auto args = std::make_shared<HilPlayArgs>();
  CLI::App* cmd = app.add_subcommand(
      "hil-play",
      "Play a dive back into the hardware: serial sensors into pseudo-terminals (a symlink "
      "each), CAN sensors onto SocketCAN, at the recorded times; writes a navd config pointing "
      "at them (hil-tests/README.md). Run navd --config <that config> beside it.");
  cmd->add_option("dive", args->dive, "dive directory (dive.lcmlog + config.yaml) or its log")
      ->required();
  cmd->add_option("--speed", args->speed, "x real time (default 1; != 1 distorts navd's time)")
      ->check(CLI::Range(1e-3, 1000.0));
  cmd->add_option("--serial-dir", args->serial_dir,
                  "directory of the pty links <dir>/<sensor name> (default DIVE/hil)");
  cmd->add_option("--can-interface", args->can_interface,
                  "SocketCAN interface for CAN sensors (default vcan0)");
  cmd->add_option("--config-out", args->config_out,
                  "navd config to write (default <serial dir>/navd-hil.yaml)");
  cmd->add_option("--lcm-url", args->lcm_url, "lcm.url of the written navd config");
  cmd->add_flag("--no-wait", args->no_wait,
                "start at once instead of when every pty has a reader (navd opened them)");
  cmd->add_flag("--play-registrations", args->play_registrations,
                "publish the log's NAV_REGISTRATION on --lcm-url at their log times (they "
                "answer no proposal of the running navd, which rejects them as another run's: "
                "docs/formats.md \"Provenance of registrations\")");
  cmd->add_flag("--no-camera", args->no_camera,
                "do not serve camera_gige sensors with Aravis' fake GigE camera on lo");
  cmd->add_option("--camera-image-dir", args->camera_image_dir,
                  "where navd writes the camera frames it receives (camera.image_dir of the "
                  "written config; default <serial dir>/images, 'none': not written)");
  cmd->add_option("--reader-timeout-s", args->reader_timeout_s,
                  "give up waiting for readers after this long (default 0: wait)")
      ->check(CLI::Range(0.0, 86400.0));
  cmd->add_flag("--hold", args->hold,
                "after the log ends keep the ptys and the camera open until Ctrl-C / SIGTERM "
                "(navd sees the sensors fall silent instead of vanishing)");
  cmd->add_flag("--json", args->json, "print the playback report as JSON on stdout");
  cmd->callback([args] { run_hil_play(*args); });
}

const CommandRegistration kRegister{"hil-play", add_hil_play};

}  // namespace
}  // namespace nav::tool
