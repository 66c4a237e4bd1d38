#pragma once
// navd on the vehicle: the device threads of the sensors with a hardware transport
// (nav/daemon/service/navd_devices.h) feed the same MeasurementQueue -> TimeOrderingBuffer
// (filter.latency_window_ms) -> NavFilter -> Publisher / LinkPublisher path as navd --replay,
// paced by the devices themselves. Camera links come from an asynchronous vision stage
// (registration_listener.h: registration_t on lcm.channels.registration into the filter
// thread's RegistrationTable; pairs waiting for an answer, filter.registration_wait_s, on
// lcm.channels.link_proposals). Recovery runs inside NavFilter per image
// (filter.cg_iterations_per_step; on its recovery thread with filter.recovery_thread), as in
// --replay.
// With `checkpoints`, the SLAM filter resumes
// from the newest valid checkpoint of input "live" in checkpoint.path and writes checkpoints
// there (checkpoint.period_s, at shutdown), as --replay --checkpoints does for a log.
// sd_notify READY/WATCHDOG (from the main thread, so a quiet sensor set keeps the watchdog fed)
// and STOPPING; SIGTERM/SIGINT or `duration_s` stop it. One line of JSON goes to stdout at the
// end: {"mode":"live","measurements":...,"images":...,"links":...,"devices":...,"wall_s":...,
// "links_accepted":...,"registrations":...,"pairs_deferred":...} (registration_summary_json).
// Exit status: 0 stopped, 1 the filter failed.

#include <csignal>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/daemon/system/sd_notify.h"

namespace nav::daemon::service {

struct LiveModeArgs {
  std::string config_path;
  double duration_s = 0.0;   ///< 0: until a stop signal
  bool checkpoints = false;  ///< resume from / write checkpoint.path (identity "live")
};

/// True when at least one configured sensor has a hardware transport (not `sim`).
bool has_device_sensors(const daemon::NavdConfig& config);

int run_live_mode(const daemon::NavdConfig& config, const LiveModeArgs& args,
                  const sigset_t& stop_signals, const daemon::SdNotifier& notifier);

}  // namespace nav::daemon::service
