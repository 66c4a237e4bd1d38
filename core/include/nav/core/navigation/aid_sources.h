#pragma once
// The robot's aid sources, one small function each, in the manner of PX4 EKF2's aid sources
// (src/modules/ekf2/EKF/aid_sources/): each turns a sensor message into an observation of the
// robot state (measurement z, noise R and the measurement model with the sensor's mount), the
// filter computes the innovation and its variance into a uniform status (innovation_stats.h),
// then fuses it into the ESDF unless the update is rejected (Eustice et al., RSS 2005 sec. III:
// DVL body velocities, attitude and depth as unary updates of the robot block).
// * DVL: bottom-track velocity in the DVL frame, DvlVelocityModel with mount and lever arm.
// * Roll/pitch and heading: the body attitude of an attitude message (SensorModels::
//   body_attitude: the sensor frame's angles rotated by the mount; partial messages completed).
// * Depth: pressure depth of the sensor, DepthModel with the lever arm.
// Altitude sets the camera footprint size (no seabed model); angular rates are not used.

#include <cstddef>

#include "nav/core/models/measurement.h"
#include "nav/core/models/unary_models.h"
#include "nav/core/navigation/aid_gate.h"
#include "nav/core/navigation/sensor_measurements.h"
#include "nav/core/navigation/sensor_models.h"

namespace nav::core {

/// One observation of the robot ready to fuse.
template <class Model>
struct AidObservation {
  Model model;
  MeasVec z;
  MeasCov R;
  const char* kind;    ///< "DVL", "roll/pitch", "heading", "depth" (string literals)
  AidKind gate_kind;   ///< its innovation gate (aid_gate.h)
  std::size_t sensor;  ///< index into NavFilterOptions::sensors
};

/// Throws std::out_of_range for a sensor index outside the sensors.
AidObservation<DvlVelocityModel> dvl_velocity_aid(const SensorModels& sensors,
                                                  const DvlVelocity& m);
/// `body` must have has_roll_pitch.
AidObservation<AttitudeModel> roll_pitch_aid(const SensorModels& sensors, std::size_t sensor,
                                             const BodyAttitude& body);
/// `body` must have has_heading.
AidObservation<HeadingModel> heading_aid(const SensorModels& sensors, std::size_t sensor,
                                         const BodyAttitude& body);
AidObservation<DepthModel> depth_aid(const SensorModels& sensors, const Depth& m);

/// Calls fuse(observation) for each aid `m` carries (a DVL velocity; the roll/pitch and the
/// heading of an attitude; a depth) and returns true; false for anything else (altitude, angular
/// rates, images). Throws std::out_of_range for a sensor index outside the sensors. `sensors`
/// remembers partial attitude messages (SensorModels::body_attitude).
template <class Fuse>
bool for_each_aid(SensorModels& sensors, const Measurement& m, Fuse&& fuse) {
  if (const auto* dvl = std::get_if<DvlVelocity>(&m)) {
    fuse(dvl_velocity_aid(sensors, *dvl));
  } else if (const auto* att = std::get_if<Attitude>(&m)) {
    const BodyAttitude body = sensors.body_attitude(*att);
    if (body.has_roll_pitch) fuse(roll_pitch_aid(sensors, att->time.sensor_index, body));
    if (body.has_heading) fuse(heading_aid(sensors, att->time.sensor_index, body));
  } else if (const auto* depth = std::get_if<Depth>(&m)) {
    fuse(depth_aid(sensors, *depth));
  } else {
    return false;
  }
  return true;
}

}  // namespace nav::core
