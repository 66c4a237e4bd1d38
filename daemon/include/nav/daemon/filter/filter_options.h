#pragma once
// navd's configuration of the navigation filter (core::NavFilter, nav/core/navigation/): the
// YAML config (config.h) mapped to the plain core::NavFilterOptions, and the names the daemon
// uses for the filter's types.

#include "nav/core/navigation/nav_filter.h"
#include "nav/daemon/config/config.h"

namespace nav::daemon {

using core::ImageRecord;
using core::InnovationComponent;
using core::innovation_period;
using core::InnovationPeriod;
using core::LinkOutcome;
using core::LinkRecord;
using core::NavFilter;
using core::NavFilterCounters;
using core::NavFilterOptions;
using core::PendingRegistration;
using core::PendingRegistrationCounters;
using core::ProposalRecord;
using core::SensorInnovation;
using core::to_string;

/// The filter options of `config`:
/// * sensors: each config sensor's mount (rotation, lever arm), noise sigmas and, for cameras,
///   the intrinsics (footprint for link proposal);
/// * process_noise = filter.process_noise_psd; recovery: fixed filter.cg_iterations_per_step
///   PCG iterations per image;
/// * camera_gate_chi2 = the 5-dof gate at the probability of the 6-dof
///   filter.gating_chi2_threshold (chi_square.h);
/// * aid_gate = filter.{dvl,roll_pitch,heading,depth}_gate_sigma, filter.aid_gate_reset_s;
/// * recovery_thread / recovery_handoff_s / registration_wait_s / max_pending_registrations
///   from filter.*; with recovery_thread the jobs run on a RecoveryWorker thread
///   (recovery_worker.h);
/// * warnings go to the log (spdlog).
core::NavFilterOptions filter_options_from_config(const NavdConfig& config);

}  // namespace nav::daemon
