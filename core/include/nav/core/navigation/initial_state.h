#pragma once
// The robot's prior at the start of a dive, shared by NavFilter and DeadReckoningFilter
// (nav_filter.h "Initialisation"): measurements are held until a roll/pitch, a heading and a
// depth have been seen; the filter then starts at the first held measurement's time (the world
// origin) with x = y = 0, z from the depth minus the lever arm, the attitude from the attitude
// sensor, velocities and rates 0, and replays every held measurement.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/core/navigation/nav_filter_options.h"
#include "nav/core/navigation/sensor_measurements.h"
#include "nav/core/navigation/sensor_models.h"
#include "nav/core/status.h"

namespace nav::core {

/// Measurements held until the first attitude, heading and depth (the fields are checkpointed
/// by NavFilter, nav_filter_serialization.h).
struct HeldInitialisation {
  static constexpr std::size_t kMaxHeld = 1024;

  std::optional<BodyAttitude> roll_pitch, heading;
  std::optional<Depth> depth;
  std::size_t roll_pitch_sensor = 0, heading_sensor = 0;
  std::vector<Measurement> held;
  std::int64_t first_time_us = 0;

  /// Holds m and notes its attitude or depth; false when kMaxHeld are held (m is dropped, its
  /// attitude or depth still noted).
  bool hold(const Measurement& m, SensorModels& sensors);
  bool ready() const { return roll_pitch && heading && depth; }
  /// Once the filter has started: hands every held measurement to process(m) in order and
  /// forgets them; `counted` (the filter's measurement counter) is first reduced by their number,
  /// as process counts them again. Returns the first error.
  template <class Process>
  Status replay(std::uint64_t& counted, Process&& process);
};

struct RobotPrior {
  Vec12 x0 = Vec12::Zero();
  Mat12 P0 = Mat12::Identity();
};

/// The prior of `init` (ready()): x, y at 0 with initial_xy_sigma_m; z from the depth minus the
/// lever arm; the attitude from the sensors; the attitude and depth sigmas 10x the sensors' (the
/// messages are applied again as updates when the held measurements are replayed); velocities
/// and rates 0 with their initial sigmas.
RobotPrior initial_robot_prior(const HeldInitialisation& init, const SensorModels& sensors,
                               const NavFilterOptions& options);

template <class Process>
Status HeldInitialisation::replay(std::uint64_t& counted, Process&& process) {
  std::vector<Measurement> replayed;
  replayed.swap(held);
  counted -= replayed.size();
  for (const Measurement& m : replayed) {
    if (Status s = process(m); !s.ok()) return s;
  }
  return Status::Ok();
}

}  // namespace nav::core
