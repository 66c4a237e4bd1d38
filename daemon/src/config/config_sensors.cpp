// navd config: the `sensors:` list (type, transport, mount, noise, camera). See config.h and
// config/README.md for the schema.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "config_sections.h"

namespace nav::daemon::detail {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr std::array<int, 11> kStandardBauds{1200,  2400,   4800,   9600,   19200, 38400,
                                             57600, 115200, 230400, 460800, 921600};

SensorType parse_type(const YamlReader& sensor) {
  SensorType type = SensorType::kDvlPd0;
  if (!sensor.has("type")) sensor.at("type");  // throws "missing required key"
  sensor.read_enum("type", type,
                   {{"dvl_pd0", SensorType::kDvlPd0},
                    {"dvl_pd6", SensorType::kDvlPd6},
                    {"dvl_can", SensorType::kDvlCan},
                    {"heading_nmea", SensorType::kHeadingNmea},
                    {"fog_kvh", SensorType::kFogKvh},
                    {"pressure_paro", SensorType::kPressureParo},
                    {"altimeter", SensorType::kAltimeter},
                    {"camera_gige", SensorType::kCameraGige},
                    {"camera_v4l2", SensorType::kCameraV4l2}});
  return type;
}

/// The transport kind a sensor type needs on hardware ("sim" is always allowed).
std::string_view hardware_transport(SensorType type) {
  switch (type) {
    case SensorType::kDvlCan:
      return "can";
    case SensorType::kCameraGige:
      return "gige";
    case SensorType::kCameraV4l2:
      return "v4l2";
    default:
      return "serial";
  }
}

SerialTransport parse_serial(const YamlReader& t) {
  t.expect_map({"type", "device", "baud", "parity", "flow"});
  SerialTransport serial;
  t.read("device", serial.device, true);
  t.read("baud", serial.baud, 1, 4000000);
  if (t.has("baud") && std::find(kStandardBauds.begin(), kStandardBauds.end(), serial.baud) ==
                           kStandardBauds.end()) {
    t.at("baud").fail(std::to_string(serial.baud) +
                      " is not a standard baud rate (1200, 2400, ... 115200, 230400, 460800, "
                      "921600)");
  }
  t.read_enum("parity", serial.parity,
              {{"none", Parity::kNone}, {"even", Parity::kEven}, {"odd", Parity::kOdd}});
  t.read_enum("flow", serial.flow,
              {{"none", FlowControl::kNone},
               {"rtscts", FlowControl::kRtsCts},
               {"xonxoff", FlowControl::kXonXoff}});
  return serial;
}

/// Resolves the signal table path and loads it; its errors are reported at the key.
void load_can_signals(const YamlReader& t, CanTransport& can, const std::string& base_dir) {
  std::filesystem::path file(can.signals_file);
  if (file.is_relative() && !base_dir.empty()) file = std::filesystem::path(base_dir) / file;
  can.signals_file = file.string();
  try {
    can.signals = drivers::load_can_config_file(can.signals_file);
  } catch (const drivers::CanConfigError& e) {
    t.at("signals_file").fail(e.what());
  }
}

Transport parse_transport(const YamlReader& sensor, SensorType type, const std::string& base_dir) {
  const YamlReader t = sensor.at("transport");
  if (!t.node().IsMap()) t.fail("expected a mapping with a type key");
  const std::string kind = t.at("type").as_string();
  const std::string_view expected = hardware_transport(type);
  if (kind != "sim" && kind != expected) {
    t.at("type").fail("'" + kind + "' is not valid for a " + to_string(type) + " sensor (use " +
                      std::string(expected) + " or sim)");
  }
  if (kind == "sim") {
    t.expect_map({"type"});
    return SimTransport{};
  }
  if (kind == "serial") return parse_serial(t);
  if (kind == "can") {
    t.expect_map({"type", "interface", "signals_file"});
    CanTransport can;
    t.read("interface", can.interface, true);
    t.read("signals_file", can.signals_file, true);
    load_can_signals(t, can, base_dir);
    return can;
  }
  if (kind == "gige") {
    t.expect_map({"type", "camera_id"});
    GigeTransport gige;
    t.read("camera_id", gige.camera_id, true);
    return gige;
  }
  t.expect_map({"type", "device"});
  V4l2Transport v4l2;
  t.read("device", v4l2.device, true);
  return v4l2;
}

std::array<double, 3> read_vec3(const YamlReader& r, double limit, double scale) {
  const std::vector<YamlReader> items = r.elements();
  if (items.size() != 3) r.fail("expected 3 numbers, got " + std::to_string(items.size()));
  std::array<double, 3> out{};
  for (std::size_t i = 0; i < 3; ++i) {
    const double v = items[i].as_double();
    if (std::abs(v) > limit) {
      std::string reason = "|";
      reason += std::to_string(v);
      reason += "| exceeds ";
      reason += std::to_string(limit);
      items[i].fail(reason);
    }
    out[i] = v * scale;
  }
  return out;
}

Mount parse_mount(const YamlReader& m) {
  m.expect_map({"rotation_deg", "lever_arm_m"});
  Mount mount;
  if (m.has("rotation_deg")) mount.rpy_rad = read_vec3(m.at("rotation_deg"), 360.0, kDegToRad);
  if (m.has("lever_arm_m")) mount.lever_arm_m = read_vec3(m.at("lever_arm_m"), 100.0, 1.0);
  return mount;
}

void read_deg(const YamlReader& n, std::string_view key, double& out_rad) {
  double deg = out_rad / kDegToRad;
  n.read(key, deg, 1e-6, 90.0);
  out_rad = deg * kDegToRad;
}

/// Each sensor type accepts the noise keys of what it measures (Table II defaults otherwise).
NoiseSigmas parse_noise(const YamlReader& n, SensorType type) {
  NoiseSigmas noise;
  switch (type) {
    case SensorType::kDvlPd0:
    case SensorType::kDvlPd6:
    case SensorType::kDvlCan:
      n.expect_map({"velocity_mps"});
      break;
    case SensorType::kHeadingNmea:
    case SensorType::kFogKvh:
      n.expect_map({"roll_pitch_deg", "heading_deg"});
      break;
    case SensorType::kPressureParo:
      n.expect_map({"depth_m"});
      break;
    case SensorType::kAltimeter:
      n.expect_map({"altitude_m"});
      break;
    case SensorType::kCameraGige:
    case SensorType::kCameraV4l2:
      n.expect_map({"pixel_px"});
      break;
  }
  n.read("velocity_mps", noise.velocity_mps, 1e-6, 10.0);
  read_deg(n, "roll_pitch_deg", noise.roll_pitch_rad);
  read_deg(n, "heading_deg", noise.heading_rad);
  n.read("depth_m", noise.depth_m, 1e-6, 100.0);
  n.read("altitude_m", noise.altitude_m, 1e-6, 100.0);
  n.read("pixel_px", noise.pixel_px, 1e-3, 100.0);
  return noise;
}

CameraConfig parse_camera(const YamlReader& c) {
  c.expect_map({"fx", "fy", "cx", "cy", "distortion", "pixel_format", "trigger", "frame_rate_hz",
                "image_dir"});
  CameraConfig cam;
  c.read("fx", cam.fx_px, 1e-3, 1e6, true);
  c.read("fy", cam.fy_px, 1e-3, 1e6, true);
  c.read("cx", cam.cx_px, 0.0, 1e5, true);
  c.read("cy", cam.cy_px, 0.0, 1e5, true);
  if (c.has("distortion")) {
    const YamlReader d = c.at("distortion");
    for (const YamlReader& k : d.elements()) cam.distortion.push_back(k.as_double());
    const std::size_t n = cam.distortion.size();
    if (n != 0 && n != 4 && n != 5 && n != 8) {
      d.fail(std::to_string(n) +
             " coefficients; expected 0, 4, 5 or 8 (k1 k2 p1 p2 [k3 [k4 k5 k6]])");
    }
  }
  c.read_enum("pixel_format", cam.pixel_format,
              {{"mono8", PixelFormat::kMono8},
               {"mono12", PixelFormat::kMono12},
               {"mono16", PixelFormat::kMono16},
               {"bayer_rg8", PixelFormat::kBayerRg8},
               {"rgb8", PixelFormat::kRgb8}});
  c.read_enum("trigger", cam.trigger,
              {{"free_run", Trigger::kFreeRun},
               {"software", Trigger::kSoftware},
               {"hardware", Trigger::kHardware}});
  c.read("frame_rate_hz", cam.frame_rate_hz, 1e-3, 100.0);
  c.read("image_dir", cam.image_dir);
  return cam;
}

PressureConfig parse_pressure(const YamlReader& p) {
  p.expect_map({"latitude_deg", "surface_pressure_dbar"});
  PressureConfig pressure;
  p.read("latitude_deg", pressure.latitude_deg, -90.0, 90.0);
  p.read("surface_pressure_dbar", pressure.surface_pressure_dbar, 0.0, 20.0);
  return pressure;
}

SensorConfig parse_sensor(const YamlReader& s, const std::string& base_dir) {
  s.expect_map({"name", "type", "transport", "mount", "noise", "camera", "pressure", "latency_ms"});
  SensorConfig sensor;
  s.read("name", sensor.name, true);
  sensor.type = parse_type(s);
  sensor.transport = parse_transport(s, sensor.type, base_dir);
  if (s.has("mount")) sensor.mount = parse_mount(s.at("mount"));
  if (s.has("noise")) sensor.noise = parse_noise(s.at("noise"), sensor.type);
  if (is_camera(sensor.type)) {
    sensor.camera = parse_camera(s.at("camera"));
  } else if (s.has("camera")) {
    s.at("camera").fail(std::string("only camera sensors take a camera block, this is ") +
                        to_string(sensor.type));
  }
  if (s.has("pressure")) {
    if (sensor.type != SensorType::kPressureParo) {
      s.at("pressure")
          .fail(std::string("only pressure_paro sensors take a pressure block, this is ") +
                to_string(sensor.type));
    }
    sensor.pressure = parse_pressure(s.at("pressure"));
  }
  double latency_ms = sensor.latency_s * 1e3;
  s.read("latency_ms", latency_ms, 0.0, 10000.0);
  sensor.latency_s = latency_ms * 1e-3;
  return sensor;
}

}  // namespace

std::vector<SensorConfig> parse_sensors(const YamlReader& list, const std::string& base_dir) {
  std::vector<SensorConfig> sensors;
  const std::vector<YamlReader> items = list.elements();
  if (items.empty()) list.fail("at least one sensor is required");
  for (const YamlReader& item : items) {
    SensorConfig sensor = parse_sensor(item, base_dir);
    for (const SensorConfig& other : sensors) {
      if (other.name == sensor.name)
        item.at("name").fail("duplicate sensor name '" + sensor.name + "'");
    }
    sensors.push_back(std::move(sensor));
  }
  return sensors;
}

}  // namespace nav::daemon::detail
