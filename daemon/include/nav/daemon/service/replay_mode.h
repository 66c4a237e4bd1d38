#pragma once
// navd --replay DIVE.lcmlog: the recorded dive through the same source, time ordering and
// NavFilter as `navtool replay` (replay/dive_replay.h), published on LCM as on the vehicle
// (Publisher: nav_solution_t, health_t; LinkPublisher: camera_link_t, delayed_state_bound_t,
// bounds_snapshot_t), with sd_notify READY/WATCHDOG/STOPPING, SIGTERM/SIGINT stop. At the end
// the replay's JSON summary goes to stdout and, with --out, the replay output directory is
// written. Used by navd --replay and by `navtool survey` (which writes its report afterwards:
// the report is not part of the vehicle binary). Exit status: 0 done or stopped, 1 the filter
// failed.

#include <csignal>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/daemon/system/sd_notify.h"

namespace nav::daemon::service {

struct ReplayModeArgs {
  std::string log_path;
  std::string config_path;
  double speed = 1.0;
  bool as_fast_as_possible = false;
  std::string out_dir;
  bool checkpoints = false;         ///< --checkpoints: resume from / write checkpoint.path
  std::string checkpoint_identity;  ///< "": the log path (ReplayOptions::checkpoint_identity)
  int time_of_use_every_images = 0;  ///< ReplayOptions::time_of_use_every_images
  bool time_of_use_markov_blanket = false;
};

int run_replay_mode(const daemon::NavdConfig& config, const ReplayModeArgs& args,
                    const sigset_t& stop_signals, const daemon::SdNotifier& notifier);

}  // namespace nav::daemon::service
