// hil_navd_config_yaml: rewrites the transports of a dive's config for navd's live mode.
#include "navd_config_yaml.h"

#include <yaml-cpp/yaml.h>

#include <stdexcept>

namespace nav::hil {
namespace {

const PlayedSensor* find_sensor(const std::vector<PlayedSensor>& sensors, const std::string& name) {
  for (const PlayedSensor& s : sensors) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

YAML::Node serial_transport(const YAML::Node& recorded, const PlayedSensor& sensor) {
  YAML::Node t;
  t["type"] = "serial";
  t["device"] = sensor.device.string();
  const bool was_serial = recorded["type"] && recorded["type"].as<std::string>() == "serial";
  t["baud"] = was_serial && recorded["baud"] ? recorded["baud"].as<int>() : 115200;
  for (const char* key : {"parity", "flow"}) {
    if (was_serial && recorded[key]) t[key] = recorded[key].as<std::string>();
  }
  return t;
}

YAML::Node can_transport(const YAML::Node& recorded, const PlayedSensor& sensor,
                         const std::filesystem::path& config_dir) {
  YAML::Node t;
  t["type"] = "can";
  t["interface"] = sensor.device.string();
  if (recorded["signals_file"]) {
    std::filesystem::path table = recorded["signals_file"].as<std::string>();
    if (table.is_relative()) table = std::filesystem::absolute(config_dir / table);
    t["signals_file"] = table.string();
  }
  return t;
}

YAML::Node gige_transport(const PlayedSensor& sensor) {
  YAML::Node t;
  t["type"] = "gige";
  t["camera_id"] = sensor.device.string();
  return t;
}

YAML::Node played_transport(const YAML::Node& recorded, const PlayedSensor& sensor,
                            const std::filesystem::path& config_dir) {
  switch (sensor.output) {
    case SensorOutput::kPty:
      return serial_transport(recorded, sensor);
    case SensorOutput::kCan:
      return can_transport(recorded, sensor, config_dir);
    case SensorOutput::kGige:
      return gige_transport(sensor);
    case SensorOutput::kNotPlayed:
      break;
  }
  YAML::Node t;
  t["type"] = "sim";  // navd's live mode opens no device for it
  return t;
}

}  // namespace

std::string hil_navd_config_yaml(const std::string& dive_config_yaml,
                                 const std::filesystem::path& dive_config_dir,
                                 const std::vector<PlayedSensor>& sensors,
                                 const std::string& lcm_url,
                                 const std::filesystem::path& camera_image_dir) {
  YAML::Node root = YAML::Load(dive_config_yaml);
  if (!root.IsMap() || !root["sensors"] || !root["sensors"].IsSequence()) {
    throw std::runtime_error("dive config: not a YAML map with a sensors list");
  }
  for (YAML::Node sensor : root["sensors"]) {
    const std::string name = sensor["name"] ? sensor["name"].as<std::string>() : "";
    const PlayedSensor* played = find_sensor(sensors, name);
    if (!played) throw std::runtime_error("dive config: sensor '" + name + "' has no plan");
    sensor["transport"] = played_transport(sensor["transport"], *played, dive_config_dir);
    if (played->output == SensorOutput::kGige) {
      YAML::Node camera = sensor["camera"];
      camera["trigger"] = "hardware";  // the player is the trigger line (fake_gige_camera.h)
      if (!camera_image_dir.empty()) camera["image_dir"] = camera_image_dir.string();
    }
  }
  root.remove("sim");
  root["lcm"]["url"] = lcm_url;
  // A vision stage answers navd's proposals after the image (live mode): let pairs wait.
  if (!root["filter"]["registration_wait_s"]) root["filter"]["registration_wait_s"] = 10.0;
  YAML::Emitter out;
  out << root;
  return "# navd config for hardware-in-the-loop playback (navtool hil-play,\n"
         "# hil-tests/README.md); generated from the dive's config.yaml.\n" +
         std::string(out.c_str()) + "\n";
}

}  // namespace nav::hil
