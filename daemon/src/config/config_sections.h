#pragma once
// Internal to nav_daemon: section parsers of the navd config (config.cpp, config_sensors.cpp).

#include <string>
#include <vector>

#include "nav/daemon/config/config.h"
#include "yaml_reader.h"

namespace nav::daemon::detail {

/// `base_dir` resolves relative file names (CAN signal tables).
std::vector<SensorConfig> parse_sensors(const YamlReader& list, const std::string& base_dir);

}  // namespace nav::daemon::detail
