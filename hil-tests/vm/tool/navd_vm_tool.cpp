// navd_vm_tool: the two helpers the navd test VM needs beyond navd and navtool
// (hil-tests/vm/README.md).
//
//   navd_vm_tool can-dive IN_DIVE OUT_DIVE SIGNALS_FILE
//     Copies the simulated dive IN_DIVE (navtool simulate) to OUT_DIVE with its PD0 DVL moved
//     onto a CAN bus as SIGNALS_FILE's table lays it out (config/can/dvl_fog_example.yaml):
//     per valid bottom-track ensemble a dvl_time frame (the ensemble's RTC as the 32-bit ms
//     counter, ping_seq = ensemble number mod 256) then a dvl_velocity frame (velocity over
//     ground in the instrument frame = minus the PD0 bottom track, bottom_track_valid = 1), and
//     a FOG's fog_time (RTC as the 32-bit us counter) + fog_attitude frame (the ensemble's
//     heading, pitch, roll) on the same bus. Every frame is one candump line in its own
//     RAW_<DVL> event at the ensemble's host times, so `navtool hil-play` sends it as one frame.
//     The DVL sensor of OUT_DIVE/config.yaml becomes type dvl_can on transport
//     {type: can, interface: vcan0, signals_file: SIGNALS_FILE}; every other event is copied.
//     Prints one JSON line: ensembles, dvl_frames, dvl_velocity_frames, fog_frames.
//
//   navd_vm_tool health LCM_LOG
//     The last NAVD_HEALTH message (navlcm::health_t) of an LCM log (lcm-logger), one line per
//     sensor: "<name> records=R bytes=B measurements=M updates=U rejected=X decode_errors=E".
//     Exit 1 when the log has no NAVD_HEALTH message.
//
//   navd_vm_tool solutions LCM_LOG
//     Every NAVD_SOLUTION message (navlcm::nav_solution_t) of an LCM log, one line each:
//     "<utime_us> <time_of_validity_us> <num_delayed_states> <filter_status>" (utime: the
//     publisher's CLOCK_REALTIME, so a line tells which navd process sent it). Exit 1 when the
//     log has none.
//
//   navd_vm_tool checkpoint CONFIG DIR
//     What a restarted navd would resume from: the newest checkpoint of DIR that decodes into a
//     filter built from CONFIG (navd's own resume_nav_filter(), input identity "live"), as
//     "path=P delayed_states=N images=I validity_us=T applied=K"; delayed states = the ESDF's
//     blocks minus the robot's, as NAVD_SOLUTION counts them (link_publisher.cpp). Exit 1 when
//     no checkpoint decodes.
//
//   navd_vm_tool tty-release TTY...
//     Clears the exclusive mode (ioctl TIOCNXCL) of each terminal, as root: what the kernel's
//     last close does to a real serial port when the navd holding it dies. The HIL player's
//     pseudo-terminals outlive that close (the player keeps their masters open), so the
//     TIOCEXCL a killed navd set stays and the restarted navd's open() gets EBUSY. Exit 1 with
//     the terminal and errno when one fails.
#include <fcntl.h>
#include <sys/ioctl.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/health_t.hpp>
#include <navlcm/nav_solution_t.hpp>
#include <string>
#include <variant>
#include <vector>

#include "nav/daemon/checkpoint/nav_filter_checkpointer.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/log/dive_log.h"
#include "nav/drivers/codecs/can_signals.h"
#include "nav/drivers/codecs/candump_log.h"
#include "nav/drivers/codecs/pd0.h"
#include "nav/drivers/config/can_config.h"

namespace {

namespace fs = std::filesystem;
using nav::drivers::CanMessageSpec;
using nav::drivers::CanSignalInput;

constexpr const char* kInterface = "vcan0";

const CanMessageSpec& message(const nav::drivers::CanConfig& table, const std::string& name) {
  for (const CanMessageSpec& m : table.messages)
    if (m.name == name) return m;
  throw std::runtime_error("the CAN signal table has no message '" + name + "'");
}

struct CanDiveCounts {
  std::int64_t ensembles = 0, dvl_frames = 0, dvl_velocity_frames = 0, fog_frames = 0;
};

/// Writes the DVL's and FOG's frames for one PD0 ensemble into the dive log.
class CanDvlWriter {
 public:
  CanDvlWriter(const nav::drivers::CanConfig& table, std::string sensor,
               nav::daemon::DiveLogWriter& out)
      : dvl_time_(message(table, "dvl_time")),
        dvl_velocity_(message(table, "dvl_velocity")),
        fog_time_(message(table, "fog_time")),
        fog_attitude_(message(table, "fog_attitude")),
        sensor_(std::move(sensor)),
        out_(out) {}

  void write(const nav::drivers::Pd0Ensemble& e, const navlcm::raw_bytes_t& raw,
             CanDiveCounts& n) {
    ++n.ensembles;
    const auto& bt = e.bottom_track;
    if (!bt || !bt->velocity_valid() || !e.time.sensor_time_us) return;
    const std::int64_t rtc_us = *e.time.sensor_time_us;
    const double seq = static_cast<double>(e.ensemble_number % 256);
    const double time_ms_s = static_cast<double>((rtc_us / 1000) % (std::int64_t{1} << 32)) * 1e-3;
    frame(dvl_time_, {{"time_s", time_ms_s}, {"ping_seq", seq}}, raw);
    frame(dvl_velocity_,
          {{"v_x_mps", -*bt->velocity_mps[0]},
           {"v_y_mps", -*bt->velocity_mps[1]},
           {"v_z_mps", -*bt->velocity_mps[2]},
           {"bottom_track_valid", 1.0},
           {"beams_used", 4.0},
           {"ping_seq", seq}},
          raw);
    n.dvl_frames += 2;
    ++n.dvl_velocity_frames;
    if (!e.heading_rad || !e.pitch_rad || !e.roll_rad) return;
    const double time_us_s = static_cast<double>(rtc_us % (std::int64_t{1} << 32)) * 1e-6;
    frame(fog_time_, {{"time_s", time_us_s}, {"seq", seq}}, raw);
    frame(fog_attitude_,
          {{"heading_rad", *e.heading_rad},
           {"roll_rad", *e.roll_rad},
           {"pitch_rad", *e.pitch_rad},
           {"fog_ok", 1.0},
           {"aligned", 1.0},
           {"seq", seq}},
          raw);
    n.fog_frames += 2;
  }

 private:
  void frame(const CanMessageSpec& spec, std::initializer_list<CanSignalInput> values,
             const navlcm::raw_bytes_t& raw) {
    const std::vector<CanSignalInput> v(values);
    const auto data = nav::drivers::encode_can_message(spec, v);
    if (!data) throw std::runtime_error("cannot encode CAN message " + spec.name);
    nav::drivers::CanLogFrame f;
    f.id = spec.id;
    f.extended = spec.extended;
    f.dlc = static_cast<std::uint8_t>(data->size());
    std::copy(data->begin(), data->end(), f.data.begin());
    f.time.realtime_us = raw.utime;
    f.time.monotonic_us = raw.host_monotonic_us;
    std::snprintf(f.interface_name.data(), f.interface_name.size(), "%s", kInterface);
    // docs/formats.md: one candump log line per frame, newline-terminated (the dive-log
    // source's stream decoder needs the newline; format_candump_log_line gives none).
    const std::string line = nav::drivers::format_candump_log_line(f) + "\n";
    out_.write_raw(sensor_, raw.utime, raw.host_monotonic_us,
                   {reinterpret_cast<const std::uint8_t*>(line.data()), line.size()});
  }

  const CanMessageSpec &dvl_time_, &dvl_velocity_, &fog_time_, &fog_attitude_;
  std::string sensor_;
  nav::daemon::DiveLogWriter& out_;
};

/// config.yaml of the CAN dive: the first dvl_pd0 sensor becomes dvl_can on vcan0. Its name.
std::string write_can_config(const fs::path& in, const fs::path& out, const fs::path& signals) {
  YAML::Node config = YAML::LoadFile(in.string());
  for (YAML::Node sensor : config["sensors"]) {
    if (sensor["type"].as<std::string>() != "dvl_pd0") continue;
    sensor["type"] = "dvl_can";
    YAML::Node transport;
    transport["type"] = "can";
    transport["interface"] = kInterface;
    transport["signals_file"] = fs::absolute(signals).string();
    sensor["transport"] = transport;
    std::ofstream(out) << "# " << in.string() << " with its DVL on CAN (navd_vm_tool can-dive)\n"
                       << config << "\n";
    return sensor["name"].as<std::string>();
  }
  throw std::runtime_error(in.string() + ": no dvl_pd0 sensor to move onto CAN");
}

int can_dive(const fs::path& in, const fs::path& out, const fs::path& signals) {
  fs::create_directories(out);
  const std::string dvl = write_can_config(in / "config.yaml", out / "config.yaml", signals);
  const nav::drivers::CanConfig table = nav::drivers::load_can_config_file(signals.string());
  nav::daemon::DiveLogReader reader((in / "dive.lcmlog").string());
  nav::daemon::DiveLogWriter writer((out / "dive.lcmlog").string());
  CanDvlWriter can(table, dvl, writer);
  nav::drivers::Pd0Decoder pd0;
  std::vector<nav::drivers::Pd0Ensemble> ensembles;
  CanDiveCounts n;
  while (auto event = reader.next()) {
    if (const auto* raw = std::get_if<navlcm::raw_bytes_t>(&*event)) {
      if (raw->device != dvl) {
        writer.write_raw(raw->device, raw->utime, raw->host_monotonic_us, raw->data);
        continue;
      }
      ensembles.clear();
      pd0.feed(raw->data, {raw->host_monotonic_us, raw->utime}, ensembles);
      for (const auto& e : ensembles) can.write(e, *raw, n);
    } else if (const auto* image = std::get_if<navlcm::image_metadata_t>(&*event)) {
      writer.write(*image);
    } else {
      writer.write(std::get<navlcm::registration_t>(*event));
    }
  }
  std::printf(
      "{\"ensembles\":%lld,\"dvl_frames\":%lld,\"dvl_velocity_frames\":%lld,\"fog_frames\":%lld}\n",
      static_cast<long long>(n.ensembles), static_cast<long long>(n.dvl_frames),
      static_cast<long long>(n.dvl_velocity_frames), static_cast<long long>(n.fog_frames));
  return n.dvl_velocity_frames > 0 ? 0 : 1;
}

int health(const std::string& path) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error(path + ": cannot open as an LCM log");
  navlcm::health_t last;
  bool found = false;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != "NAVD_HEALTH") continue;
    if (last.decode(e->data, 0, e->datalen) < 0)
      throw std::runtime_error(path + ": a NAVD_HEALTH message does not decode as health_t");
    found = true;
  }
  if (!found) {
    std::fprintf(stderr, "navd_vm_tool health: %s has no NAVD_HEALTH message\n", path.c_str());
    return 1;
  }
  for (const navlcm::sensor_health_t& s : last.sensors) {
    std::printf("%s records=%lld bytes=%lld measurements=%lld updates=%lld rejected=%lld "
                "decode_errors=%lld\n",
                s.name.c_str(), static_cast<long long>(s.records),
                static_cast<long long>(s.bytes), static_cast<long long>(s.measurements),
                static_cast<long long>(s.updates), static_cast<long long>(s.rejected_updates),
                static_cast<long long>(s.decode_errors));
  }
  return 0;
}

int solutions(const std::string& path) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error(path + ": cannot open as an LCM log");
  long long count = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != "NAVD_SOLUTION") continue;
    navlcm::nav_solution_t msg;
    if (msg.decode(e->data, 0, e->datalen) < 0)
      throw std::runtime_error(path + ": a NAVD_SOLUTION message does not decode as nav_solution_t");
    std::printf("%lld %lld %d %d\n", static_cast<long long>(msg.utime),
                static_cast<long long>(msg.time_of_validity_us), msg.num_delayed_states,
                static_cast<int>(msg.filter_status));
    ++count;
  }
  if (count == 0) {
    std::fprintf(stderr, "navd_vm_tool solutions: %s has no NAVD_SOLUTION message\n", path.c_str());
    return 1;
  }
  return 0;
}

int checkpoint(const std::string& config_path, const std::string& dir) {
  const nav::daemon::NavdConfig config = nav::daemon::load_config_file(config_path);
  const nav::daemon::NavFilterOptions options = nav::daemon::filter_options_from_config(config);
  // No registration table: decoding needs none (pending pairs are not checkpointed).
  auto make = [&] { return std::make_unique<nav::daemon::NavFilter>(options, nullptr); };
  const nav::daemon::ResumedNavFilter resumed = nav::daemon::resume_nav_filter(dir, make, "live");
  for (const nav::daemon::SkippedCheckpoint& k : resumed.skipped) {
    std::fprintf(stderr, "navd_vm_tool checkpoint: %s skipped: %s\n", k.path.c_str(),
                 k.reason.c_str());
  }
  if (!resumed.filter) {
    std::fprintf(stderr, "navd_vm_tool checkpoint: no checkpoint in %s decodes with %s\n",
                 dir.c_str(), config_path.c_str());
    return 1;
  }
  std::printf("path=%s delayed_states=%d images=%zu validity_us=%lld applied=%llu\n",
              resumed.path.c_str(), resumed.filter->esdf().num_blocks() - 1,
              resumed.filter->images().size(),
              static_cast<long long>(resumed.point.validity_us),
              static_cast<unsigned long long>(resumed.point.applied));
  return 0;
}

int tty_release(const std::vector<std::string>& ttys) {
  int failed = 0;
  for (const std::string& tty : ttys) {
    const int fd = ::open(tty.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0 || ::ioctl(fd, TIOCNXCL) != 0) {
      std::fprintf(stderr, "navd_vm_tool tty-release: %s: %s %s\n", tty.c_str(),
                   fd < 0 ? "open" : "ioctl TIOCNXCL", std::strerror(errno));
      ++failed;
    }
    if (fd >= 0) ::close(fd);
  }
  return failed == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.size() == 4 && args[0] == "can-dive") return can_dive(args[1], args[2], args[3]);
    if (args.size() == 2 && args[0] == "health") return health(args[1]);
    if (args.size() == 2 && args[0] == "solutions") return solutions(args[1]);
    if (args.size() == 3 && args[0] == "checkpoint") return checkpoint(args[1], args[2]);
    if (args.size() >= 2 && args[0] == "tty-release") return tty_release({args.begin() + 1, args.end()});
  } catch (const std::exception& e) {
    std::fprintf(stderr, "navd_vm_tool %s: %s\n", args[0].c_str(), e.what());
    return 1;
  }
  std::fprintf(stderr,
               "usage: navd_vm_tool can-dive IN_DIVE OUT_DIVE SIGNALS_FILE\n"
               "       navd_vm_tool health LCM_LOG\n"
               "       navd_vm_tool solutions LCM_LOG\n"
               "       navd_vm_tool checkpoint CONFIG DIR\n"
               "       navd_vm_tool tty-release TTY...\n");
  return 2;
}
