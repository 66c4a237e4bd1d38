// navd's device-thread glue (nav/daemon/service/navd_devices.h).
#include "nav/daemon/service/navd_devices.h"

#include <spdlog/spdlog.h>

#include <lcm/lcm-cpp.hpp>

namespace nav::daemon::service {

NavdDevices::NavdDevices(const daemon::NavdConfig& config, daemon::MeasurementQueue& queue)
    : health_(config), lcm_(std::make_unique<lcm::LCM>(config.lcm.url)) {
  if (!lcm_->good()) {
    spdlog::error("navd: cannot open LCM at '{}' for raw sensor bytes; not publishing them",
                  config.lcm.url);
  }
  sources_ = std::make_unique<daemon::DeviceSources>(config, queue,
                                                     lcm_->good() ? lcm_.get() : nullptr, health_);
}

NavdDevices::~NavdDevices() { join(); }

}  // namespace nav::daemon::service
