#pragma once
// The filter's view of the sensors: core measurement models with each sensor's mount and noise
// (SensorModelOptions), looked up by MeasurementTime::sensor_index (an index into
// NavFilterOptions::sensors). Built once at start-up; no allocation afterwards.
//
// Frames (core/README.md): R_body_sensor from the mount's Z-Y-X Euler angles, lever arm in body.
// * DVL: DvlVelocityModel with R_body_dvl and the lever arm (velocity in the DVL frame).
// * Attitude/heading: the sensor reports the Euler angles of ITS frame in world; the body's are
//   R_world_body = R_world_sensor R_body_sensorᵀ. A partial message (heading-only HDT or
//   roll/pitch-only PHTRO) is completed with that sensor's last other angles before rotating
//   (exact for a zero mount rotation, where the angles pass through unchanged).
// * Depth: DepthModel with the lever arm.
// * Camera: CameraRelativePoseModel with x_body_camera = [lever arm, rotation]; the
//   footprint half-diagonal per metre of altitude, sqrt((cx/fx)² + (cy/fy)²), for link proposal
//   (assumes a near-vertical optical axis, as on the survey vehicles).

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/core/models/binary_models.h"
#include "nav/core/models/measurement.h"
#include "nav/core/models/unary_models.h"
#include "nav/core/navigation/sensor_measurements.h"

namespace nav::core {

/// Pinhole intrinsics of a camera, pixels (only what link proposal needs: the footprint).
struct CameraIntrinsics {
  double fx_px = 0.0, fy_px = 0.0, cx_px = 0.0, cy_px = 0.0;
};

/// One sensor: its mount (Z-Y-X Euler angles of the sensor frame in body, lever arm in body)
/// and measurement noise sigmas; `camera` set for a camera.
struct SensorModelOptions {
  std::string name;  ///< for messages
  Vec3 rpy_body_sensor_rad = Vec3::Zero();
  Vec3 p_body_sensor_m = Vec3::Zero();
  double roll_pitch_sigma_rad = 0.1 * 3.14159265358979323846 / 180.0;
  double heading_sigma_rad = 0.1 * 3.14159265358979323846 / 180.0;
  double velocity_sigma_mps = 0.01;
  double depth_sigma_m = 0.01;
  std::optional<CameraIntrinsics> camera;
};

struct BodyAttitude {  ///< attitude of the body from one attitude message
  double roll_rad = 0.0, pitch_rad = 0.0, heading_rad = 0.0;
  bool has_roll_pitch = false, has_heading = false;
};

class SensorModels {
 public:
  /// Throws std::invalid_argument naming the sensor when a camera has no usable calibration.
  explicit SensorModels(const std::vector<SensorModelOptions>& sensors);

  std::size_t num_sensors() const { return sensors_.size(); }
  /// Config name of sensor `index` ("sensor#<index>" when out of range), for messages.
  std::string name(std::size_t index) const;

  const DvlVelocityModel& dvl(std::size_t index) const { return at(index).dvl; }
  const MeasCov& dvl_noise(std::size_t index) const { return at(index).R_dvl; }
  const DepthModel& depth(std::size_t index) const { return at(index).depth; }
  const MeasCov& depth_noise(std::size_t index) const { return at(index).R_depth; }
  const MeasCov& roll_pitch_noise(std::size_t index) const { return at(index).R_roll_pitch; }
  const MeasCov& heading_noise(std::size_t index) const { return at(index).R_heading; }

  /// The body attitude of an attitude message (see the file comment); remembers the message's
  /// angles for completing later partial messages of the same sensor.
  BodyAttitude body_attitude(const Attitude& m);

  /// The first camera of the sensors (its mount and calibration), or nullopt without a camera.
  const std::optional<CameraRelativePoseModel>& camera() const { return camera_; }
  /// Footprint half-diagonal per metre of altitude of the first camera (0 without a camera).
  double footprint_radius_per_altitude() const { return footprint_per_altitude_; }

  /// The state carried between messages, both ways (core/serialization/archive.h): each
  /// sensor's last angles. Reading requires the same number of sensors.
  template <class Archive>
  void serialize(Archive& ar) {
    std::uint64_t n = sensors_.size();  // u64 on every platform
    ar(n, "sensor count");
    if (!ar.check(n == sensors_.size(), "checkpoint has " + std::to_string(n) +
                                            " sensors, the filter " +
                                            std::to_string(sensors_.size()))) {
      return;
    }
    for (Sensor& s : sensors_) ar(s.last_rpy_sensor, "sensor last angles");
  }

 private:
  struct Sensor {
    std::string name;
    Mat3 R_body_sensor = Mat3::Identity();
    bool rotated = false;  ///< mount rotation not zero
    DvlVelocityModel dvl;
    DepthModel depth;
    MeasCov R_dvl, R_depth, R_roll_pitch, R_heading;
    Vec3 last_rpy_sensor = Vec3::Zero();  ///< last angles seen (attitude sensors)
  };
  const Sensor& at(std::size_t index) const;
  Sensor& at(std::size_t index);

  std::vector<Sensor> sensors_;
  std::optional<CameraRelativePoseModel> camera_;
  double footprint_per_altitude_ = 0.0;
};

}  // namespace nav::core
