// Config sensors -> core measurement models (see sensor_models.h).
#include "nav/daemon/filter/sensor_models.h"

#include <cmath>
#include <stdexcept>

#include "nav/core/geometry/rotation.h"

namespace nav::daemon {
namespace {

core::MeasCov diagonal(int dim, double sigma) {
  core::MeasCov R = core::MeasCov::Zero(dim, dim);
  for (int i = 0; i < dim; ++i) R(i, i) = sigma * sigma;
  return R;
}

core::Vec3 to_vec3(const std::array<double, 3>& a) { return core::Vec3(a[0], a[1], a[2]); }

}  // namespace

SensorModels::SensorModels(const NavdConfig& config) {
  sensors_.reserve(config.sensors.size());
  for (const SensorConfig& c : config.sensors) {
    Sensor s;
    s.name = c.name;
    const core::Vec3 rpy = to_vec3(c.mount.rpy_rad);
    const core::Vec3 lever_m = to_vec3(c.mount.lever_arm_m);
    s.R_body_sensor = core::rotation_from_euler(rpy);
    s.rotated = rpy.norm() > 0.0;
    s.dvl.R_body_dvl = s.R_body_sensor;
    s.dvl.p_body_dvl_m = lever_m;
    s.depth.p_body_sensor_m = lever_m;
    s.R_dvl = diagonal(3, c.noise.velocity_mps);
    s.R_depth = diagonal(1, c.noise.depth_m);
    s.R_roll_pitch = diagonal(2, c.noise.roll_pitch_rad);
    s.R_heading = diagonal(1, c.noise.heading_rad);
    if (is_camera(c.type) && !camera_) {
      const CameraConfig& cam = c.camera;
      if (!(cam.fx_px > 0.0 && cam.fy_px > 0.0)) {
        throw std::invalid_argument("sensor '" + c.name + "': camera focal lengths must be > 0");
      }
      core::CameraRelativePoseModel model;
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
  core::Vec3 rpy = s.last_rpy_sensor;
  if (s.rotated) {
    rpy = core::euler_from_rotation(core::rotation_from_euler(rpy) * s.R_body_sensor.transpose());
  }
  out.roll_rad = rpy(0);
  out.pitch_rad = rpy(1);
  out.heading_rad = rpy(2);
  return out;
}

}  // namespace nav::daemon
