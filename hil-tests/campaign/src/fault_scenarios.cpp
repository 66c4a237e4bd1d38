// The campaign's scenarios; see fault_scenarios.h. Windows: the standard dive (107 s) has
// its faults from 30 s (60-s faults from 25 s), the long dive (845 s) its 10-min DVL outage
// from 60 s, the short dive (43 s) from 15 s: the filter has initialised and taken images
// before, and there is dive left after to see it recover.
#include "nav/campaign/fault_scenarios.h"

#include <cmath>

namespace nav::campaign {
namespace {

using hil::FaultKind;
using hil::PlayerFault;

FaultScenario sensor_fault(std::string name, std::string description, FaultKind kind,
                           std::string sensor, double from_s, double to_s, double value,
                           Detector detector) {
  FaultScenario s;
  s.name = std::move(name);
  s.description = std::move(description);
  s.from_s = from_s;
  s.to_s = to_s;
  s.player_faults.push_back(PlayerFault{kind, sensor, from_s, to_s, value});
  s.sensor = std::move(sensor);
  s.detector = detector;
  s.uncertainty_must_grow = kind == FaultKind::kDrop && s.sensor == "dvl";
  return s;
}

FaultScenario host_fault(std::string name, std::string description, HostFault host, double from_s,
                         double to_s) {
  FaultScenario s;
  s.name = std::move(name);
  s.description = std::move(description);
  s.from_s = from_s;
  s.to_s = to_s;
  s.host = host;
  return s;
}

/// The played GigE camera destroyed for the window and started again (player_faults.h).
FaultScenario camera_vanish(std::string name, double from_s, double to_s) {
  FaultScenario s = sensor_fault(std::move(name), "", FaultKind::kCameraVanish, "camera", from_s,
                                 to_s, 0, Detector::kDisconnected);
  s.description =
      "fake GigE camera destroyed for " + std::to_string(int(to_s - from_s)) + " s, started again";
  s.must_reconnect = true;
  s.no_late_measurements = true;
  return s;
}

/// navd's wall clock stepped by `step_s` at `from_s` (it stays stepped).
FaultScenario clock_step(std::string name, double step_s, double from_s, double to_s) {
  FaultScenario s = host_fault(std::move(name), "", HostFault::kClockStep, from_s, to_s);
  s.description = std::string("navd's CLOCK_REALTIME stepped ") + (step_s > 0 ? "+" : "-") +
                  std::to_string(int(std::abs(step_s))) + " s (CLOCK_MONOTONIC runs on)";
  s.clock_step_s = step_s;
  s.detector = Detector::kWallClockJump;
  s.no_late_measurements = true;
  return s;
}

}  // namespace

const char* to_string(HostFault fault) {
  switch (fault) {
    case HostFault::kNone:
      return "none";
    case HostFault::kCpuSaturation:
      return "cpu_saturation";
    case HostFault::kRouteRemoved:
      return "route_removed";
    case HostFault::kCheckpointDiskFull:
      return "checkpoint_disk_full";
    case HostFault::kKillRestart:
      return "kill_restart";
    case HostFault::kClockStep:
      return "clock_step";
  }
  return "?";
}

const char* to_string(Detector detector) {
  switch (detector) {
    case Detector::kSilent:
      return "last_message_age_s > 1 or !connected";
    case Detector::kDisconnected:
      return "!connected or reconnects++";
    case Detector::kRejected:
      return "rejected_updates++ / decode_errors++ / nis_mean > 4 x expected";
    case Detector::kWallClockJump:
      return "status: wall clock jumped";
    case Detector::kNone:
      return "-";
  }
  return "?";
}

std::vector<FaultScenario> standard_scenarios(bool short_version) {
  if (short_version) {
    return {sensor_fault("dvl_dropout_15s", "DVL silent for 15 s", FaultKind::kDrop, "dvl", 15, 30,
                         0, Detector::kSilent),
            sensor_fault("depth_spikes_10m", "depth +-10 m on every reply for 10 s",
                         FaultKind::kDepthSpike, "depth", 15, 25, 10, Detector::kRejected),
            sensor_fault("heading_unplug_10s", "heading pty closed 10 s, reopened",
                         FaultKind::kUnplug, "heading", 15, 25, 0, Detector::kDisconnected)};
  }
  std::vector<FaultScenario> s{
      sensor_fault("dvl_dropout_60s", "DVL silent for 60 s", FaultKind::kDrop, "dvl", 25, 85, 0,
                   Detector::kSilent),
      sensor_fault("dvl_dropout_10min", "DVL silent for 10 min (long dive)", FaultKind::kDrop,
                   "dvl", 60, 660, 0, Detector::kSilent),
      sensor_fault("dvl_garbage_10s", "DVL bottom-track velocities random +-2 m/s for 10 s",
                   FaultKind::kGarbage, "dvl", 30, 40, 2.0, Detector::kRejected),
      sensor_fault("heading_stuck_30s", "heading stuck at 45 deg for 30 s",
                   FaultKind::kHeadingStuck, "heading", 30, 60, 45.0 * M_PI / 180.0,
                   Detector::kRejected),
      sensor_fault("depth_spikes_10m", "depth +-10 m on every reply for 20 s",
                   FaultKind::kDepthSpike, "depth", 30, 50, 10, Detector::kRejected),
      sensor_fault("dvl_unplug_20s", "DVL pty closed 20 s, reopened", FaultKind::kUnplug, "dvl", 30,
                   50, 0, Detector::kDisconnected),
      host_fault("cpu_saturation_60s", "both cores busy (2 spinning processes) for 60 s",
                 HostFault::kCpuSaturation, 25, 85),
      host_fault("multicast_route_20s", "route 224.0.0.0/4 deleted for 20 s",
                 HostFault::kRouteRemoved, 30, 50),
      host_fault("checkpoint_disk_full", "checkpoint tmpfs full (ENOSPC) for 40 s",
                 HostFault::kCheckpointDiskFull, 30, 70),
      host_fault("sigkill_restart", "SIGKILL at a random moment, restart with --checkpoints",
                 HostFault::kKillRestart, 40, 70)};
  s[1].long_dive = true;
  s.push_back(camera_vanish("camera_vanish_30s", 30, 60));
  s.push_back(clock_step("clock_step_+2s", +2.0, 30, 50));
  s.push_back(clock_step("clock_step_-2s", -2.0, 30, 50));
  return s;
}

int dive_images(bool short_version, bool long_dive) {
  if (short_version) return 6;
  return long_dive ? 90 : 14;
}

}  // namespace nav::campaign
