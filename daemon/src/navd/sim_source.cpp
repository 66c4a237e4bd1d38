#include "navd/sim_source.h"

#include <chrono>
#include <cmath>
#include <ctime>
#include <thread>

namespace nav::navd {
namespace {

std::int64_t clock_us(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000 + ts.tv_nsec / 1000;
}

daemon::MeasurementTime stamp(std::int64_t validity_us, int sensor) {
  daemon::MeasurementTime t;
  t.validity_us = validity_us;
  t.host_monotonic_us = monotonic_us();
  t.host_realtime_us = realtime_us();
  t.sensor_index = static_cast<std::uint16_t>(sensor);
  return t;
}

/// Sleeps until survey time `t_us` is due (or stop); in fast mode waits for queue room instead.
void pace(std::int64_t t_us, std::int64_t wall_start_us, const SimSourceOptions& options,
          const daemon::MeasurementQueue& queue, const std::atomic<bool>& stop) {
  using std::chrono::microseconds;
  if (options.as_fast_as_possible) {
    while (!stop.load() && queue.size() > queue.capacity() / 2) {
      std::this_thread::sleep_for(microseconds(200));
    }
    return;
  }
  const auto due_us = wall_start_us + static_cast<std::int64_t>(std::llround(t_us / options.speed));
  for (std::int64_t now = monotonic_us(); now < due_us && !stop.load(); now = monotonic_us()) {
    std::this_thread::sleep_for(microseconds(std::min<std::int64_t>(due_us - now, 10'000)));
  }
}

void push_navigation(const core::sim::SurveyStep& step, std::int64_t t_us,
                     const SimSensorIndices& s, daemon::MeasurementQueue::Producer& producer) {
  if (s.dvl >= 0) {
    daemon::DvlVelocity dvl;
    dvl.time = stamp(t_us, s.dvl);
    for (int i = 0; i < 3; ++i) dvl.v_sensor_mps[static_cast<size_t>(i)] = step.dvl(i);
    producer.push(dvl);
  }
  if (s.attitude >= 0) {
    daemon::Attitude att;
    att.time = stamp(t_us, s.attitude);
    att.roll_rad = step.attitude(0);
    att.pitch_rad = step.attitude(1);
    att.heading_rad = step.heading(0);
    producer.push(att);
  }
  if (s.depth >= 0) {
    daemon::Depth depth;
    depth.time = stamp(t_us, s.depth);
    depth.depth_m = step.depth(0);
    producer.push(depth);
  }
}

}  // namespace

std::int64_t monotonic_us() { return clock_us(CLOCK_MONOTONIC); }
std::int64_t realtime_us() { return clock_us(CLOCK_REALTIME); }

SimSensorIndices find_sim_sensors(const daemon::NavdConfig& config) {
  using daemon::SensorType;
  SimSensorIndices s;
  for (size_t i = 0; i < config.sensors.size(); ++i) {
    const int idx = static_cast<int>(i);
    switch (config.sensors[i].type) {
      case SensorType::kDvlPd0:
      case SensorType::kDvlPd6:
      case SensorType::kDvlCan:
        if (s.dvl < 0) s.dvl = idx;
        break;
      case SensorType::kHeadingNmea:
      case SensorType::kFogKvh:
        if (s.attitude < 0) s.attitude = idx;
        break;
      case SensorType::kPressureParo:
        if (s.depth < 0) s.depth = idx;
        break;
      case SensorType::kCameraGige:
      case SensorType::kCameraV4l2:
        if (s.camera < 0) s.camera = idx;
        break;
      case SensorType::kAltimeter:
        break;  // the survey simulates no altitude
    }
  }
  return s;
}

std::vector<std::int64_t> step_start_times_us(const core::sim::Survey& survey) {
  std::vector<std::int64_t> t_us(survey.steps.size() + 1, 0);
  double t_s = 0.0;
  for (size_t k = 0; k < survey.steps.size(); ++k) {
    t_s += survey.steps[k].dt_s;
    t_us[k + 1] = std::llround(t_s * 1e6);
  }
  return t_us;
}

void run_sim_source(const core::sim::Survey& survey, const SimSensorIndices& sensors,
                    const SimSourceOptions& options, daemon::MeasurementQueue& queue,
                    const std::atomic<bool>& stop, std::atomic<bool>& done) {
  auto producer = queue.make_producer("sim");
  const std::vector<std::int64_t> t_us = step_start_times_us(survey);
  const std::int64_t wall_start_us = monotonic_us();
  for (size_t k = 0; k < survey.steps.size() && !stop.load(); ++k) {
    const core::sim::SurveyStep& step = survey.steps[k];
    if (step.image >= 0 && sensors.camera >= 0) {
      pace(t_us[k], wall_start_us, options, queue, stop);
      daemon::ImageEvent image;
      image.time = stamp(t_us[k], sensors.camera);
      image.frame_id = static_cast<std::uint64_t>(step.image);
      producer.push(image);
    }
    pace(t_us[k + 1], wall_start_us, options, queue, stop);
    if (stop.load()) break;
    push_navigation(step, t_us[k + 1], sensors, producer);
  }
  done.store(true);
}

}  // namespace nav::navd
