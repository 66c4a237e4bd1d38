#pragma once
// The filter's view of the configured sensors: core measurement models with each sensor's
// mount (config `mount`) and noise (config `noise`), looked up by MeasurementTime::sensor_index
// (an index into NavdConfig::sensors). Built once at start-up; no allocation afterwards.
//
// Frames (core/README.md): R_body_sensor from the mount's Z-Y-X Euler angles, lever arm in body.
// * DVL: core::DvlVelocityModel with R_body_dvl and the lever arm (velocity in the DVL frame).
// * Attitude/heading: the sensor reports the Euler angles of ITS frame in world; the body's are
//   R_world_body = R_world_sensor R_body_sensorᵀ. A partial message (heading-only HDT or
//   roll/pitch-only PHTRO) is completed with that sensor's last other angles before rotating
//   (exact for a zero mount rotation, where the angles pass through unchanged).
// * Depth: core::DepthModel with the lever arm.
// * Camera: core::CameraRelativePoseModel with x_body_camera = [lever arm, rotation]; the
//   footprint half-diagonal per metre of altitude, sqrt((cx/fx)² + (cy/fy)²), for link proposal
//   (assumes a near-vertical optical axis, as on the survey vehicles).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/core/models/binary_models.h"
#include "nav/core/models/measurement.h"
#include "nav/core/models/unary_models.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/measurement.h"

namespace nav::daemon {

struct BodyAttitude {  ///< attitude of the body from one attitude message
  double roll_rad = 0.0, pitch_rad = 0.0, heading_rad = 0.0;
  bool has_roll_pitch = false, has_heading = false;
};

class SensorModels {
 public:
  /// Throws std::invalid_argument naming the sensor when a camera has no usable calibration.
  explicit SensorModels(const NavdConfig& config);

  std::size_t num_sensors() const { return sensors_.size(); }
  /// Config name of sensor `index` ("sensor#<index>" when out of range), for messages.
  std::string name(std::size_t index) const;

  const core::DvlVelocityModel& dvl(std::size_t index) const { return at(index).dvl; }
  const core::MeasCov& dvl_noise(std::size_t index) const { return at(index).R_dvl; }
  const core::DepthModel& depth(std::size_t index) const { return at(index).depth; }
  const core::MeasCov& depth_noise(std::size_t index) const { return at(index).R_depth; }
  const core::MeasCov& roll_pitch_noise(std::size_t index) const { return at(index).R_roll_pitch; }
  const core::MeasCov& heading_noise(std::size_t index) const { return at(index).R_heading; }

  /// The body attitude of an attitude message (see the file comment); remembers the message's
  /// angles for completing later partial messages of the same sensor.
  BodyAttitude body_attitude(const Attitude& m);

  /// The first camera of the config (its mount and calibration), or nullopt without a camera.
  const std::optional<core::CameraRelativePoseModel>& camera() const { return camera_; }
  /// Footprint half-diagonal per metre of altitude of the first camera (0 without a camera).
  double footprint_radius_per_altitude() const { return footprint_per_altitude_; }

 private:
  friend struct NavFilterCheckpointAccess;  // checkpoints: nav_filter_checkpoint.cpp
  struct Sensor {
    std::string name;
    core::Mat3 R_body_sensor = core::Mat3::Identity();
    bool rotated = false;  ///< mount rotation not zero
    core::DvlVelocityModel dvl;
    core::DepthModel depth;
    core::MeasCov R_dvl, R_depth, R_roll_pitch, R_heading;
    core::Vec3 last_rpy_sensor = core::Vec3::Zero();  ///< last angles seen (attitude sensors)
  };
  const Sensor& at(std::size_t index) const;
  Sensor& at(std::size_t index);

  std::vector<Sensor> sensors_;
  std::optional<core::CameraRelativePoseModel> camera_;
  double footprint_per_altitude_ = 0.0;
};

}  // namespace nav::daemon
