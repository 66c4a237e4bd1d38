// DivePlayer: schedules a dive log's RAW_<NAME> messages onto ptys and SocketCAN at their
// recorded host times; see dive_player.h.
#include "nav/hil/dive_player.h"

#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <variant>

#include "camera_playback.h"
#include "can_output.h"
#include "fake_gige_camera.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/log/dive_log.h"
#include "nav/daemon/system/host_clock.h"
#include "nav/hil/pty_link.h"
#include "navd_config_yaml.h"

namespace nav::hil {
namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot read");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool is_serial_type(daemon::SensorType type) {
  using T = daemon::SensorType;
  return type == T::kDvlPd0 || type == T::kDvlPd6 || type == T::kHeadingNmea ||
         type == T::kFogKvh || type == T::kPressureParo || type == T::kAltimeter;
}

/// The rendered frame's size along an axis: twice the principal point (renderer.h).
int frame_size_px(double principal_point_px) {
  return std::clamp(static_cast<int>(std::lround(2.0 * principal_point_px)), 1, 2048);
}

}  // namespace

std::string PlayerOptions::validate() const {
  if (!(speed > 0.0 && speed <= 1000.0)) {
    return "speed " + std::to_string(speed) + " is not in (0, 1000]";
  }
  if (can_interface.empty()) return "can_interface is empty";
  if (reader_timeout.count() < 0) return "reader_timeout is negative";
  if (!registration_lcm_url.empty() && registration_channel.empty()) {
    return "registration_channel is empty";
  }
  if (repeat < 1) return "repeat " + std::to_string(repeat) + " is < 1";
  if (repeat > 1 && fake_gige_camera) {
    return "repeat > 1 needs fake_gige_camera = false (the camera's schedule is one pass)";
  }
  for (const PlayerFault& f : faults) {
    if (std::string why = f.validate(); !why.empty()) return why;
  }
  return {};
}

struct DivePlayer::Impl {
  PlayerOptions options;
  fs::path log_path, config_path;
  std::string config_text;
  std::vector<PlayedSensor> sensors;
  std::map<std::string, std::size_t> by_name;
  std::map<std::size_t, std::unique_ptr<PtyLink>> ptys;  ///< by sensor index
  CanOutput can;
  FakeGigeCamera camera;
  std::unique_ptr<lcm::LCM> registration_lcm;       ///< registration_lcm_url, when set
  std::unique_ptr<CameraPlayback> camera_playback;  ///< when the camera is played
  std::vector<std::int64_t> fault_counts;           ///< messages per options.faults entry
  /// Playback state: the last written message's (shifted) dive time and host time, the log's
  /// realtime - monotonic offset (from the raw messages: registrations carry only a realtime
  /// utime).
  std::int64_t last_dive_us = 0, last_write_us = 0;
  std::optional<std::int64_t> realtime_minus_monotonic_us;
  /// One repetition of the log (PlayerOptions::repeat): its index and dive-time shift.
  struct Pass {
    int index = 0;
    std::int64_t shift_us = 0;
  };
  /// Plays one event at its time (shifted by the pass), updating the report.
  void play_registration(const navlcm::registration_t& reg, const Pass& pass, PlayReport& report,
                         const std::atomic<bool>& stop);
  void play_raw(navlcm::raw_bytes_t& raw, const Pass& pass, PlayReport& report,
                const std::atomic<bool>& stop);

  void resolve_paths(const fs::path& dive);
  void plan_sensors(const daemon::NavdConfig& config);
  void plan_camera(const daemon::SensorConfig& sensor, PlayedSensor& p);
  bool wait_for_readers(const std::atomic<bool>& stop) const;
  /// The dive's first message (at `dive_us`) plays now.
  void start_clock(std::int64_t dive_us, PlayReport& report) const;
  /// Whether the message went to a device.
  bool write_raw(const navlcm::raw_bytes_t& raw, PlayReport& report);
  /// The bytes to write for a message of sensor `index` at `dive_s` under the faults (empty:
  /// none); closes / reopens the sensor's pty for kUnplug.
  std::vector<std::uint8_t> faulted_bytes(std::size_t index, double dive_s,
                                          std::span<const std::uint8_t> bytes, PlayedSensor& s);
  /// Publishes a registration now, utime = the host's realtime.
  bool publish_registration(navlcm::registration_t r);
};

bool DivePlayer::Impl::publish_registration(navlcm::registration_t r) {
  r.utime = daemon::realtime_us();
  return registration_lcm->publish(options.registration_channel, &r) == 0;
}

void DivePlayer::Impl::resolve_paths(const fs::path& dive) {
  const bool dir = fs::is_directory(dive);
  log_path = dir ? dive / "dive.lcmlog" : dive;
  config_path = (dir ? dive : dive.parent_path()) / "config.yaml";
  if (!fs::exists(log_path)) throw std::runtime_error(log_path.string() + ": no such dive log");
  if (!fs::exists(config_path)) {
    throw std::runtime_error(config_path.string() + ": no config.yaml beside the dive log");
  }
  if (options.serial_dir.empty()) options.serial_dir = config_path.parent_path() / "hil";
  if (options.camera_image_dir.empty()) options.camera_image_dir = options.serial_dir / "images";
  if (options.camera_image_dir == "none") options.camera_image_dir.clear();
}

void DivePlayer::Impl::plan_sensors(const daemon::NavdConfig& config) {
  std::string can_error;
  for (const daemon::SensorConfig& s : config.sensors) {
    PlayedSensor p;
    p.name = s.name;
    p.type = daemon::to_string(s.type);
    const std::size_t index = sensors.size();
    if (is_serial_type(s.type)) {
      fs::create_directories(options.serial_dir);
      ptys[index] = std::make_unique<PtyLink>(options.serial_dir / s.name);
      p.output = SensorOutput::kPty;
      p.device = ptys[index]->link_path();
    } else if (s.type == daemon::SensorType::kDvlCan) {
      if (!can.is_open() && can_error.empty()) can_error = can.open(options.can_interface);
      p.output = can.is_open() ? SensorOutput::kCan : SensorOutput::kNotPlayed;
      p.device = options.can_interface;
      if (!can.is_open()) p.note = "CAN skipped: " + can_error;
    } else {
      plan_camera(s, p);
    }
    by_name[p.name] = index;
    sensors.push_back(std::move(p));
  }
}

void DivePlayer::Impl::plan_camera(const daemon::SensorConfig& sensor, PlayedSensor& p) {
  if (sensor.type != daemon::SensorType::kCameraGige) {
    p.note = "not played (no V4L2 loopback device is used)";
  } else if (!options.fake_gige_camera) {
    p.note = "not played (fake GigE camera disabled)";
  } else if (camera.running()) {
    p.note = "not played (the fake GigE camera serves the first camera_gige sensor only)";
  } else if (std::string why = camera.start("NAVHIL" + std::to_string(::getpid()),
                                            frame_size_px(sensor.camera.cx_px),
                                            frame_size_px(sensor.camera.cy_px));
             !why.empty()) {
    p.note = "not played: " + why;
  } else {
    p.output = SensorOutput::kGige;
    p.device = FakeGigeCamera::kAddress;
    p.note = "Aravis fake GigE camera on lo, triggered at the dive's image times";
    std::vector<PlayerFault> vanish;
    for (const PlayerFault& f : options.faults) {
      if (f.kind == FaultKind::kCameraVanish && f.sensor == sensor.name) vanish.push_back(f);
    }
    camera_playback = std::make_unique<CameraPlayback>(camera, log_path, config_path.parent_path(),
                                                       sensor.latency_s, std::move(vanish));
  }
}

bool DivePlayer::Impl::wait_for_readers(const std::atomic<bool>& stop) const {
  const std::int64_t give_up_us =
      options.reader_timeout.count() > 0
          ? daemon::monotonic_us() + options.reader_timeout.count() * 1000
          : INT64_MAX;
  while (!stop.load() && daemon::monotonic_us() < give_up_us) {
    const bool all = std::all_of(ptys.begin(), ptys.end(), [](const auto& p) {
      return p.second && p.second->reader_attached();
    });
    if (all) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

void DivePlayer::Impl::start_clock(std::int64_t dive_us, PlayReport& report) const {
  report.started = true;
  report.dive_start_us = dive_us;
  report.host_start_us = daemon::monotonic_us();
  if (camera_playback) camera_playback->start(dive_us, report.host_start_us, options.speed);
  if (options.on_start) options.on_start(report.dive_start_us, report.host_start_us);
}

std::vector<std::uint8_t> DivePlayer::Impl::faulted_bytes(std::size_t index, double dive_s,
                                                          std::span<const std::uint8_t> bytes,
                                                          PlayedSensor& s) {
  std::vector<std::uint8_t> out(bytes.begin(), bytes.end());
  bool unplugged = false;
  for (std::size_t k = 0; k < options.faults.size(); ++k) {
    const PlayerFault& f = options.faults[k];
    if (f.sensor != s.name || !f.active(dive_s)) continue;
    unplugged = unplugged || f.kind == FaultKind::kUnplug;
    out = apply_fault(f, out, fault_counts[k]++);
    ++s.faulted;
  }
  auto pty = ptys.find(index);
  if (pty != ptys.end() && unplugged && pty->second) {
    pty->second.reset();  // closes the master: the reader sees the device vanish
    ++s.unplugs;
  } else if (pty != ptys.end() && !unplugged && !pty->second) {
    pty->second = std::make_unique<PtyLink>(options.serial_dir / s.name);  // plugged back in
  }
  return out;
}

bool DivePlayer::Impl::write_raw(const navlcm::raw_bytes_t& raw, PlayReport& report) {
  const auto it = by_name.find(raw.device);
  if (it == by_name.end()) {
    ++report.raw_unknown_sensor;
    return false;
  }
  PlayedSensor& sensor = report.sensors[it->second];
  const double dive_s = (raw.host_monotonic_us - report.dive_start_us) * 1e-6;
  const std::vector<std::uint8_t> played = faulted_bytes(
      it->second, dive_s, std::span<const std::uint8_t>(raw.data.data(), raw.data.size()), sensor);
  const std::span<const std::uint8_t> bytes(played);
  if (bytes.empty()) return false;
  if (sensor.output == SensorOutput::kPty) {
    const std::size_t written = ptys.at(it->second)->write(bytes);
    sensor.bytes += static_cast<std::int64_t>(written);
    sensor.dropped_bytes += static_cast<std::int64_t>(bytes.size() - written);
  } else if (sensor.output == SensorOutput::kCan) {
    can.write(bytes, sensor);
  } else {
    return false;
  }
  ++sensor.messages;
  return true;
}

DivePlayer::DivePlayer(const fs::path& dive, PlayerOptions options)
    : impl_(std::make_unique<Impl>()) {
  if (std::string why = options.validate(); !why.empty()) {
    throw std::runtime_error("hil player options: " + why);
  }
  impl_->options = std::move(options);
  impl_->fault_counts.assign(impl_->options.faults.size(), 0);
  impl_->resolve_paths(dive);
  impl_->config_text = read_text(impl_->config_path);
  impl_->plan_sensors(daemon::load_config_file(impl_->config_path.string()));
  if (!impl_->options.registration_lcm_url.empty()) {
    impl_->registration_lcm = std::make_unique<lcm::LCM>(impl_->options.registration_lcm_url);
    if (!impl_->registration_lcm->good()) {
      throw std::runtime_error("hil player: cannot open LCM " +
                               impl_->options.registration_lcm_url + " for the registrations");
    }
  }
}

DivePlayer::~DivePlayer() = default;

const std::vector<PlayedSensor>& DivePlayer::sensors() const { return impl_->sensors; }
const fs::path& DivePlayer::log_path() const { return impl_->log_path; }
const fs::path& DivePlayer::serial_dir() const { return impl_->options.serial_dir; }

void DivePlayer::write_navd_config(const fs::path& path, const std::string& lcm_url) const {
  const std::string text =
      hil_navd_config_yaml(impl_->config_text, fs::absolute(impl_->config_path).parent_path(),
                           impl_->sensors, lcm_url, impl_->options.camera_image_dir);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out) throw std::runtime_error(path.string() + ": cannot write the navd config");
  }
  (void)daemon::load_config_file(path.string());  // navd must accept it
}

void DivePlayer::Impl::play_registration(const navlcm::registration_t& reg, const Pass& pass,
                                         PlayReport& report, const std::atomic<bool>& stop) {
  if (!registration_lcm || !report.started || !realtime_minus_monotonic_us || pass.index > 0) {
    ++report.registrations_not_played;
    return;
  }
  const double at_us =
      static_cast<double>(reg.utime - *realtime_minus_monotonic_us - report.dive_start_us);
  daemon::sleep_until_monotonic_us(report.host_start_us + std::llround(at_us / options.speed),
                                   stop);
  if (stop.load()) return;
  if (publish_registration(reg)) {
    ++report.registrations_played;
  } else {
    ++report.registrations_not_played;
  }
}

void DivePlayer::Impl::play_raw(navlcm::raw_bytes_t& raw, const Pass& pass, PlayReport& report,
                                const std::atomic<bool>& stop) {
  raw.host_monotonic_us += pass.shift_us;
  if (!realtime_minus_monotonic_us) realtime_minus_monotonic_us = raw.utime - raw.host_monotonic_us;
  if (!report.started) start_clock(raw.host_monotonic_us, report);
  const double offset_us = static_cast<double>(raw.host_monotonic_us - report.dive_start_us);
  const std::int64_t due_us = report.host_start_us + std::llround(offset_us / options.speed);
  daemon::sleep_until_monotonic_us(due_us, stop);
  if (stop.load()) return;
  last_write_us = daemon::monotonic_us();
  report.max_late_s = std::max(report.max_late_s, (last_write_us - due_us) * 1e-6);
  if (last_write_us - due_us > 10'000) ++report.late_writes;
  if (write_raw(raw, report)) last_dive_us = raw.host_monotonic_us;
}

PlayReport DivePlayer::play(const std::atomic<bool>& stop) {
  PlayReport report;
  report.sensors = impl_->sensors;
  if (impl_->options.wait_for_readers && !impl_->wait_for_readers(stop)) return report;
  std::int64_t period_us = 0;  ///< dive time from one repetition to the next
  for (int index = 0; index < impl_->options.repeat && !stop.load(); ++index) {
    if (index == 1) period_us = impl_->last_dive_us - report.dive_start_us + 1'000'000;
    const Impl::Pass pass{index, index * period_us};
    daemon::DiveLogReader reader(impl_->log_path.string());
    while (!stop.load()) {
      std::optional<daemon::DiveLogEvent> event = reader.next();
      if (!event) break;
      if (std::holds_alternative<navlcm::image_metadata_t>(*event)) ++report.images_not_played;
      if (const auto* reg = std::get_if<navlcm::registration_t>(&*event)) {
        impl_->play_registration(*reg, pass, report, stop);
      } else if (auto* raw = std::get_if<navlcm::raw_bytes_t>(&*event)) {
        impl_->play_raw(*raw, pass, report, stop);
      }
    }
  }
  if (impl_->camera_playback && report.started) {
    report.camera = impl_->camera_playback->finish(stop);
    report.images_not_played -= report.camera.images;
  }
  report.stopped = stop.load();
  if (report.started) {
    report.dive_span_s = (impl_->last_dive_us - report.dive_start_us) * 1e-6;
    report.wall_s = (impl_->last_write_us - report.host_start_us) * 1e-6;
  }
  return report;
}

}  // namespace nav::hil
