#include "nav/daemon/service/publisher.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/health_t.hpp>
#include <navlcm/nav_solution_t.hpp>
#include <thread>

#include "nav/daemon/system/host_clock.h"

namespace nav::daemon::service {
namespace {

std::int64_t period_us(double rate_hz) { return static_cast<std::int64_t>(1e6 / rate_hz); }

}  // namespace

Publisher::Publisher(const daemon::LcmConfig& config, const SolutionBoard& board,
                     const daemon::MeasurementQueue& queue)
    : config_(config), board_(board), queue_(queue), lcm_(std::make_unique<lcm::LCM>(config.url)) {}

Publisher::~Publisher() = default;

bool Publisher::good() const { return lcm_->good(); }

PublisherCounters Publisher::run(const std::atomic<bool>& stop) {
  std::int64_t next_solution_us = daemon::monotonic_us();
  std::int64_t next_health_us = next_solution_us;
  while (!stop.load()) {
    const std::int64_t now = daemon::monotonic_us();
    if (now >= next_solution_us || now >= next_health_us) {
      const SolutionView view = board_.read();
      if (now >= next_solution_us && view.has_estimate) publish_solution(view);
      if (now >= next_health_us) publish_health(view);
      if (now >= next_solution_us) next_solution_us = now + period_us(config_.nav_solution.rate_hz);
      if (now >= next_health_us) next_health_us = now + period_us(config_.health.rate_hz);
    }
    const std::int64_t wait_us =
        std::min<std::int64_t>({next_solution_us - now, next_health_us - now, 20'000});
    std::this_thread::sleep_for(std::chrono::microseconds(std::max<std::int64_t>(wait_us, 100)));
  }
  const SolutionView view = board_.read();
  if (view.has_estimate) publish_solution(view);
  publish_health(view);
  return counters_;
}

void Publisher::publish_solution(const SolutionView& view) {
  if (!good()) return;
  navlcm::nav_solution_t msg{};
  msg.utime = daemon::realtime_us();
  msg.time_of_validity_us = view.time_of_validity_us;
  for (int i = 0; i < 3; ++i) {
    msg.p_world_m[i] = view.robot_mean(i);
    msg.rph_rad[i] = view.robot_mean(3 + i);
    msg.v_body_mps[i] = view.robot_mean(6 + i);
    msg.omega_body_radps[i] = view.robot_mean(9 + i);
  }
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) msg.pose_covariance[6 * r + c] = view.robot_covariance(r, c);
  }
  msg.num_delayed_states = view.num_delayed_states;
  msg.num_camera_links = view.num_camera_links;
  msg.filter_status = static_cast<std::int8_t>(view.filter_status);
  if (lcm_->publish(config_.nav_solution.name, &msg) == 0) {
    ++counters_.solutions;
  } else {
    ++counters_.failures;
  }
}

std::string Publisher::wall_clock_status() {
  const std::int64_t monotonic = daemon::monotonic_us();
  if (const auto jump = wall_clock_.update(monotonic, daemon::realtime_us())) {
    spdlog::warn(
        "navd: wall clock (CLOCK_REALTIME) jumped by {:+.3f} s against CLOCK_MONOTONIC; "
        "measurements stay ordered by CLOCK_MONOTONIC, LCM utimes follow the wall clock",
        *jump * 1e-6);
  }
  if (wall_clock_.jumps() == 0) return {};
  return fmt::format("; wall clock jumped {} time(s), last {:+.3f} s", wall_clock_.jumps(),
                     wall_clock_.last_jump_us() * 1e-6);
}

void Publisher::publish_health(const SolutionView& view) {
  if (!good()) return;
  navlcm::health_t msg{};
  msg.utime = daemon::realtime_us();
  if (sensors_ != nullptr)
    msg.sensors = sensors_->snapshot(daemon::monotonic_us());  // device threads
  innovations_.fill(msg.sensors, view.innovations);            // and every sensor the filter used
  msg.num_sensors = static_cast<std::int32_t>(msg.sensors.size());
  msg.queue_depth = static_cast<std::int32_t>(queue_.size());
  msg.queue_capacity = static_cast<std::int32_t>(queue_.capacity());
  msg.cg_relative_residual = view.cg_relative_residual;
  msg.cg_iterations = view.cg_iterations;
  const daemon::ProcessUsageMeter::Reading usage = usage_.update();
  msg.cpu_percent = usage.cpu_percent;
  msg.rss_mb = usage.rss_mb;
  msg.peak_rss_mb = usage.peak_rss_mb;
  msg.status = view.status_line + wall_clock_status();
  if (vision_ != nullptr) {
    const daemon::vision::VisionWorkerCounters v = vision_->stats().worker;
    msg.vision_queue_depth = static_cast<std::int32_t>(v.queue_depth);
    msg.vision_latency_ms = v.latency_ms_mean;
    msg.vision_success_rate = v.success_rate();
    msg.vision_answered = static_cast<std::int64_t>(v.answered);
    msg.vision_expired = static_cast<std::int64_t>(v.expired);
    msg.vision_last_failure = v.last_failure;
  }
  if (health_fields_) health_fields_(msg);
  if (lcm_->publish(config_.health.name, &msg) == 0) {
    ++counters_.health;
  } else {
    ++counters_.failures;
  }
}

}  // namespace nav::daemon::service
