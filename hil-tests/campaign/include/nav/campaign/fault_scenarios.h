#pragma once
// The fault campaign's scenarios (docs/faults.md): one simulated dive played by the HIL player
// (nav/hil/dive_player.h) to navd live, with one fault each, either injected into the played
// bytes (nav/hil/player_faults.h) or done to navd's host (host_faults.h in src/). Each names
// the health field expected to report the fault (how `detected_after_s` is measured) and
// whether the robot's published uncertainty must grow during it (a DVL outage: dead
// reckoning without velocity).
//
// Threads: plain data.

#include <string>
#include <vector>

#include "nav/hil/player_faults.h"

namespace nav::campaign {

/// What is done to navd's host during the fault window.
enum class HostFault {
  kNone,
  kCpuSaturation,       ///< two busy-looping processes (both cores) for the window
  kRouteRemoved,        ///< the multicast route 224.0.0.0/4 deleted (network namespace)
  kCheckpointDiskFull,  ///< checkpoint.path on a small tmpfs, filled to ENOSPC
  kKillRestart,         ///< SIGKILL at a random moment of the window, restart with checkpoints
  kClockStep,           ///< navd's CLOCK_REALTIME stepped by clock_step_s at the window's start
                        ///< (navd --clock-offset-file: the host's clock is shared, not stepped)
};

/// The health_t / sensor_health_t condition that counts as "health reports the fault".
enum class Detector {
  kSilent,         ///< the sensor's last_message_age_s > 1 s or connected == false
  kDisconnected,   ///< connected == false or reconnects grew
  kRejected,       ///< the sensor's rejected_updates or decode_errors grew, or nis_mean > 4 x
                   ///< nis_expected (innovation monitoring)
  kWallClockJump,  ///< health_t.status says "wall clock jumped" (publisher.h), timed by the
                   ///< campaign's receipt of the message (its utime is the stepped clock)
  kNone,           ///< nothing in health is expected (host faults navd should ride through)
};

const char* to_string(HostFault fault);
const char* to_string(Detector detector);

struct FaultScenario {
  std::string name;         ///< e.g. "dvl_dropout_60s"
  std::string description;  ///< one line for the table
  bool long_dive = false;   ///< plays the long dive (10-min faults), else the standard one
  double from_s = 0.0;      ///< fault window, dive seconds after the first played message
  double to_s = 0.0;
  std::vector<hil::PlayerFault> player_faults;
  HostFault host = HostFault::kNone;
  std::string sensor;  ///< the sensor whose health is watched ("" for host faults)
  Detector detector = Detector::kNone;
  bool uncertainty_must_grow = false;  ///< XY sigma at the window's end > at its start
  double clock_step_s = 0.0;           ///< kClockStep: the step (s)
  /// The watched sensor must come back by itself: its reconnects >= 1 at the end and records
  /// taken after the window (camera_vanish).
  bool must_reconnect = false;
  /// No measurement may be dropped as late or for a full queue in the whole run (navd's exit
  /// summary: dropped_late, queue_dropped).
  bool no_late_measurements = false;
};

/// The full campaign (short = false) or the CI's short one: 3 scenarios on a 43-s dive.
std::vector<FaultScenario> standard_scenarios(bool short_version);

/// Images of the standard / long dive (navtool simulate --images): 14 images are a 107-s
/// dive, 90 a 845-s one (config/sim.yaml), 6 a 43-s one (the short campaign).
int dive_images(bool short_version, bool long_dive);

}  // namespace nav::campaign
