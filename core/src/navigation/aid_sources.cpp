// Sensor messages -> observations of the robot (navigation/aid_sources.h).
#include "nav/core/navigation/aid_sources.h"

namespace nav::core {
namespace {

MeasVec vec1(double a) {
  MeasVec z(1);
  z << a;
  return z;
}

}  // namespace

AidObservation<DvlVelocityModel> dvl_velocity_aid(const SensorModels& sensors,
                                                  const DvlVelocity& m) {
  const std::size_t sensor = m.time.sensor_index;
  MeasVec z(3);
  z << m.v_sensor_mps[0], m.v_sensor_mps[1], m.v_sensor_mps[2];
  return {sensors.dvl(sensor), z, sensors.dvl_noise(sensor), "DVL", AidKind::kDvl, sensor};
}

AidObservation<AttitudeModel> roll_pitch_aid(const SensorModels& sensors, std::size_t sensor,
                                             const BodyAttitude& body) {
  MeasVec z(2);
  z << body.roll_rad, body.pitch_rad;
  return {AttitudeModel{}, z, sensors.roll_pitch_noise(sensor), "roll/pitch", AidKind::kRollPitch,
          sensor};
}

AidObservation<HeadingModel> heading_aid(const SensorModels& sensors, std::size_t sensor,
                                         const BodyAttitude& body) {
  return {HeadingModel{}, vec1(body.heading_rad), sensors.heading_noise(sensor), "heading",
          AidKind::kHeading, sensor};
}

AidObservation<DepthModel> depth_aid(const SensorModels& sensors, const Depth& m) {
  const std::size_t sensor = m.time.sensor_index;
  return {sensors.depth(sensor), vec1(m.depth_m), sensors.depth_noise(sensor), "depth",
          AidKind::kDepth, sensor};
}

}  // namespace nav::core
