#pragma once
// Internal to nav_daemon: section parsers of the navd config (config.cpp, config_sensors.cpp).

#include <vector>

#include "nav/daemon/config.h"
#include "yaml_reader.h"

namespace nav::daemon::detail {

std::vector<SensorConfig> parse_sensors(const YamlReader& list);

}  // namespace nav::daemon::detail
