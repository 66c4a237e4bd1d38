// Sensor options -> core measurement models (see navigation/sensor_models.h).
#include "nav/core/navigation/sensor_models.h"

#include <cmath>
#include <stdexcept>

#include "nav/core/geometry/rotation.h"

namespace nav::core {
namespace {

MeasCov diagonal(int dim, double sigma) {
  MeasCov R = MeasCov::Zero(dim, dim);
  for (int i = 0; i < dim; ++i) R(i, i) = sigma * sigma;
  return R;
}

}  // namespace

SensorModels::SensorModels(const std::vector<SensorModelOptions>& sensors) {
  sensors_.reserve(sensors.size());
  for (const SensorModelOptions& c : sensors) {
    Sensor s;
    s.name = c.name;
    const Vec3 rpy = c.rpy_body_sensor_rad;
    const Vec3 lever_m = c.p_body_sensor_m;
    s.R_body_sensor = rotation_from_euler(rpy);
    s.rotated = rpy.norm() > 0.0;
    s.dvl.R_body_dvl = s.R_body_sensor;
    s.dvl.p_body_dvl_m = lever_m;
    s.depth.p_body_sensor_m = lever_m;
    s.R_dvl = diagonal(3, c.velocity_sigma_mps);
    s.R_depth = diagonal(1, c.depth_sigma_m);
    s.R_roll_pitch = diagonal(2, c.roll_pitch_sigma_rad);
    s.R_heading = diagonal(1, c.heading_sigma_rad);
    if (c.camera && !camera_) {
      const CameraIntrinsics& cam = *c.camera;
      if (!(cam.fx_px > 0.0 && cam.fy_px > 0.0)) {
        throw std::invalid_argument("sensor '" + c.name + "': camera focal lengths must be > 0");
      }
      CameraRelativePoseModel model;
      model.x_body_camera << lever_m, rpy;
      camera_ = model;
      footprint_per_altitude_ = std::hypot(cam.cx_px / cam.fx_px, cam.cy_px / cam.fy_px);
    }
    sensors_.push_back(std::move(s));
  }
}

std::string SensorModels::name(std::size_t index) const {
  return index < sensors_.size() ? sensors_[index].name : "sensor#" + std::to_string(index);
}

const SensorModels::Sensor& SensorModels::at(std::size_t index) const {
  if (index >= sensors_.size()) {
    throw std::out_of_range("measurement from sensor index " + std::to_string(index) +
                            ", config has " + std::to_string(sensors_.size()) + " sensors");
  }
  return sensors_[index];
}

SensorModels::Sensor& SensorModels::at(std::size_t index) {
  return const_cast<Sensor&>(static_cast<const SensorModels&>(*this).at(index));
}

BodyAttitude SensorModels::body_attitude(const Attitude& m) {
  Sensor& s = at(m.time.sensor_index);
  if (m.has_roll_pitch) {
    s.last_rpy_sensor(0) = m.roll_rad;
    s.last_rpy_sensor(1) = m.pitch_rad;
  }
  if (m.has_heading) s.last_rpy_sensor(2) = m.heading_rad;
  BodyAttitude out;
  out.has_roll_pitch = m.has_roll_pitch;
  out.has_heading = m.has_heading;
  Vec3 rpy = s.last_rpy_sensor;
  if (s.rotated) {
    rpy = euler_from_rotation(rotation_from_euler(rpy) * s.R_body_sensor.transpose());
  }
  out.roll_rad = rpy(0);
  out.pitch_rad = rpy(1);
  out.heading_rad = rpy(2);
  return out;
}

}  // namespace nav::core
