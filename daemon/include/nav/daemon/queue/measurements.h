#pragma once
// The daemon's names for the filter's measurement types (nav/core/navigation/
// sensor_measurements.h): decoders, queues and time ordering produce the core types directly,
// so the filter thread hands them to core::NavFilter without conversion.

#include "nav/core/navigation/sensor_measurements.h"

namespace nav::daemon {

using core::Altitude;
using core::AngularRate;
using core::Attitude;
using core::Depth;
using core::DvlVelocity;
using core::ImageEvent;
using core::Measurement;
using core::MeasurementTime;
using core::time_of;
using core::validity_us;

}  // namespace nav::daemon
