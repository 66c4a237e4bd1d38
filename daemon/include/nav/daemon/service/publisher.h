#pragma once
// The publisher thread: nav_solution_t and health_t (lcmtypes/) from the SolutionBoard on the
// configured channels at the configured rates (config lcm.channels). Pose covariance is the
// 6x6 [x y z roll pitch heading] block of the recovered robot covariance Σ_rr. health_t's CPU %
// is over the interval since the previous health_t (process_usage.h), RSS and peak RSS as read.
// A wall clock step seen between two health_t (wall_clock.h) is logged and, from then on,
// health_t.status ends with "; wall clock jumped N time(s), last +S.SSS s".

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "nav/daemon/config/config.h"
#include "nav/daemon/queue/measurement_queue.h"
#include "nav/daemon/service/health_innovations.h"
#include "nav/daemon/service/solution_board.h"
#include "nav/daemon/sources/sensor_health.h"
#include "nav/daemon/system/process_usage.h"
#include "nav/daemon/system/wall_clock.h"
#include "nav/daemon/vision/vision_link.h"

namespace lcm {
class LCM;
}
namespace navlcm {
class health_t;
}

namespace nav::daemon::service {

struct PublisherCounters {
  std::uint64_t solutions = 0;
  std::uint64_t health = 0;
  std::uint64_t failures = 0;  ///< publish() returned an error
};

class Publisher {
 public:
  /// Opens LCM at config.url; good() is false (and nothing is published) if that fails.
  Publisher(const daemon::LcmConfig& config, const SolutionBoard& board,
            const daemon::MeasurementQueue& queue);
  ~Publisher();
  bool good() const;
  /// Per-sensor health of the device threads, published in health_t.sensors (call before
  /// run(); the publisher thread is then the board's only snapshot reader). Null: none.
  void set_sensor_health(daemon::SensorHealthBoard* sensors) { sensors_ = sensors; }
  /// navd's own vision stage, whose counters health_t carries (vision_*). Null: none.
  void set_vision(const daemon::vision::VisionLink* vision) { vision_ = vision; }
  /// Fills further health_t fields on the publisher thread before each publish (call before
  /// run(); live mode: the registration counters, fill_registration_health()).
  void set_health_fields(std::function<void(navlcm::health_t&)> fill) {
    health_fields_ = std::move(fill);
  }
  /// Runs until `stop`, then publishes a last solution and health message.
  PublisherCounters run(const std::atomic<bool>& stop);

 private:
  void publish_solution(const SolutionView& view);
  void publish_health(const SolutionView& view);
  /// "" until a wall clock jump was seen, then its status suffix (and the jump logged).
  std::string wall_clock_status();

  daemon::LcmConfig config_;
  const SolutionBoard& board_;
  const daemon::MeasurementQueue& queue_;
  daemon::SensorHealthBoard* sensors_ = nullptr;
  const daemon::vision::VisionLink* vision_ = nullptr;
  std::function<void(navlcm::health_t&)> health_fields_;
  std::unique_ptr<lcm::LCM> lcm_;
  daemon::ProcessUsageMeter usage_;          ///< CPU % since the previous health_t
  HealthInnovations innovations_;            ///< NIS means since the previous health_t
  daemon::WallClockJumpMonitor wall_clock_;  ///< sampled at every health_t
  PublisherCounters counters_;
};

}  // namespace nav::daemon::service
