#pragma once
// Innovation fields of health_t.sensors (sensor_health_t updates, rejected_updates, nis_mean,
// nis_expected, nis_last, last[]) from NavFilter's cumulative per-sensor records
// (nav/core/navigation/innovation_stats.h). The mean NIS is over the health period: the
// difference of this snapshot and the previous one.

#include <navlcm/sensor_health_t.hpp>
#include <vector>

#include "nav/daemon/filter/filter_options.h"

namespace nav::daemon::service {

class HealthInnovations {
 public:
  /// Fills the entry of `sensors` with the same name for each record of `now` (appending an
  /// entry, other fields zero and last_message_age_s -1, for a sensor the device threads do not
  /// report, e.g. in a replay or the survey), then keeps `now` as the previous snapshot.
  void fill(std::vector<navlcm::sensor_health_t>& sensors,
            const std::vector<daemon::SensorInnovation>& now);

 private:
  std::vector<daemon::SensorInnovation> previous_;
};

}  // namespace nav::daemon::service
