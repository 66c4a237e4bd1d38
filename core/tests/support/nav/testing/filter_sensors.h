#pragma once
// The aiding sensors of the NavFilter tests: sensor models with default options (no mount
// offset, no camera), named as given, in that order (the measurements' sensor index).
#include <initializer_list>
#include <vector>

#include "nav/core/navigation/sensor_models.h"

namespace nav::testing {

inline std::vector<core::SensorModelOptions> named_sensors(
    std::initializer_list<const char*> names) {
  std::vector<core::SensorModelOptions> sensors;
  for (const char* name : names) {
    core::SensorModelOptions s;
    s.name = name;
    sensors.push_back(s);
  }
  return sensors;
}

}  // namespace nav::testing
