#include "nav/daemon/service/health_innovations.h"

namespace nav::daemon::service {
namespace {

navlcm::sensor_health_t& entry_named(std::vector<navlcm::sensor_health_t>& sensors,
                                     const std::string& name) {
  for (navlcm::sensor_health_t& s : sensors) {
    if (s.name == name) return s;
  }
  navlcm::sensor_health_t& s = sensors.emplace_back();
  s.name = name;
  s.last_message_age_s = -1.0;
  s.nis_mean = -1.0;
  s.nis_last = -1.0;
  return s;
}

const daemon::SensorInnovation* find(const std::vector<daemon::SensorInnovation>& records,
                                     std::size_t sensor) {
  for (const daemon::SensorInnovation& r : records) {
    if (r.sensor == sensor) return &r;
  }
  return nullptr;
}

navlcm::aid_source_t aid_source(const daemon::InnovationComponent& c) {
  navlcm::aid_source_t a{};
  a.time_of_validity_us = c.time_of_validity_us;
  a.observation = c.observation;
  a.observation_variance = c.observation_variance;
  a.innovation = c.innovation;
  a.innovation_variance = c.innovation_variance;
  a.test_ratio = c.test_ratio;
  a.rejected = !c.fused;
  a.fused = c.fused;
  return a;
}

}  // namespace

void HealthInnovations::fill(std::vector<navlcm::sensor_health_t>& sensors,
                             const std::vector<daemon::SensorInnovation>& now) {
  for (const daemon::SensorInnovation& r : now) {
    navlcm::sensor_health_t& s = entry_named(sensors, r.name);
    const daemon::InnovationPeriod p = daemon::innovation_period(r, find(previous_, r.sensor));
    s.updates = static_cast<std::int64_t>(r.updates);
    s.rejected_updates = static_cast<std::int64_t>(r.rejected);
    s.nis_mean = p.nis_mean;
    s.nis_expected = p.dim_mean;
    s.nis_last = r.nis_last;
    s.last.clear();
    for (int k = 0; k < r.num_components; ++k) {
      s.last.push_back(aid_source(r.last[static_cast<std::size_t>(k)]));
    }
    s.num_components = static_cast<std::int32_t>(s.last.size());
  }
  previous_ = now;
}

}  // namespace nav::daemon::service
