#include "navd/filter_loop.h"

#include <spdlog/spdlog.h>

#include <Eigen/Cholesky>
#include <chrono>
#include <cstdio>
#include <thread>

#include "nav/core/geometry/rotation.h"
#include "navd/sim_source.h"

namespace nav::navd {
namespace {

constexpr std::int64_t kStatusPeriodUs = 1'000'000;
constexpr std::size_t kPopBatch = 256;

/// Robot position error against the survey truth after `steps` steps.
double position_error_m(const core::sim::Survey& survey, size_t steps,
                        const Eigen::VectorXd& robot) {
  const core::Vec12& truth = steps == 0 ? survey.x0_true : survey.steps[steps - 1].x_true;
  return (robot.head<3>() - truth.head<3>()).norm();
}

}  // namespace

FilterLoop::FilterLoop(const core::sim::Survey& survey, daemon::MeasurementQueue& queue,
                       const daemon::TimeOrderingOptions& ordering, RecoveryInbox& inbox,
                       RecoveryOutbox& outbox, SolutionBoard& board,
                       const daemon::SdNotifier& notifier)
    : survey_(survey),
      queue_(queue),
      ordering_(ordering),
      inbox_(inbox),
      outbox_(outbox),
      board_(board),
      notifier_(notifier),
      step_start_us_(step_start_times_us(survey)),
      image_blocks_(static_cast<size_t>(survey.options.num_images), -1) {
  batch_.reserve(kPopBatch);
}

bool FilterLoop::initialise() {
  if (core::Status s = filter_.initialize(survey_.x0_mean, survey_.P0); !s.ok()) {
    fail("initialise", s);
    return false;
  }
  publish_view();
  notifier_.ready_with_status(status_line());
  return true;
}

FilterLoopResult FilterLoop::run(const std::atomic<bool>& stop,
                                 const std::atomic<bool>& source_done) {
  if (!initialise()) return finish(false);
  while (!stop.load() && error_.empty()) {
    const bool done = source_done.load();
    drain_queue();
    if (done && batch_.empty() && queue_.size() == 0) {
      while (auto m = ordering_.pop_any()) process(*m);
      if (step_open_) finish_step();
      break;
    }
    notify_systemd(false);
    if (batch_.empty()) std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  return finish(!stop.load() && error_.empty() && next_step_ == survey_.steps.size());
}

void FilterLoop::drain_queue() {
  batch_.clear();
  queue_.pop_bulk(batch_, kPopBatch);
  for (const daemon::Measurement& m : batch_) ordering_.insert(m);
  while (error_.empty()) {
    std::optional<daemon::Measurement> m = ordering_.pop_ready();
    if (!m) break;
    process(*m);
  }
}

void FilterLoop::process(const daemon::Measurement& m) {
  if (!error_.empty()) return;
  const std::int64_t t_us = daemon::validity_us(m);
  advance_to(t_us);
  const std::int64_t now_us = step_start_us_[next_step_];
  if (const auto* image = std::get_if<daemon::ImageEvent>(&m)) {
    if (t_us == now_us && image->frame_id < image_blocks_.size()) {
      pending_image_ = static_cast<int>(image->frame_id);
    } else {
      ++counters_.unmatched_measurements;
    }
    return;
  }
  if (t_us != now_us || !step_open_) {
    ++counters_.unmatched_measurements;
    return;
  }
  update_robot(m);
}

void FilterLoop::advance_to(std::int64_t t_us) {
  while (error_.empty() && next_step_ < survey_.steps.size() && step_start_us_[next_step_] < t_us) {
    if (step_open_) finish_step();
    predict_step();
  }
}

void FilterLoop::predict_step() {
  apply_recovery();
  const core::sim::SurveyStep& step = survey_.steps[next_step_];
  PredictionRecord record;
  try {
    record.robot_mean = core::sim::predicted_mean(
        survey_, step, filter_.mean_block(core::Esdf::kRobotBlock), &record.F, &record.Q);
  } catch (const std::exception& e) {
    error_ = std::string("predict step ") + std::to_string(next_step_) + ": " + e.what();
    return;
  }
  record.keep_current = pending_image_ >= 0;
  if (core::Status s = filter_.predict(record.robot_mean, record.F, record.Q, record.keep_current,
                                       &record.kept_block);
      !s.ok()) {
    fail("predict step " + std::to_string(next_step_), s);
    return;
  }
  if (record.keep_current) {
    image_blocks_[static_cast<size_t>(pending_image_)] = record.kept_block;
    ++counters_.images;
    pending_image_ = -1;
  }
  records_.push_back(record);
  ++next_step_;
  step_open_ = true;
}

void FilterLoop::update_robot(const daemon::Measurement& m) {
  const int r = core::Esdf::kRobotBlock;
  core::Status s;
  if (const auto* dvl = std::get_if<daemon::DvlVelocity>(&m)) {
    core::MeasVec z(3);
    z << dvl->v_sensor_mps[0], dvl->v_sensor_mps[1], dvl->v_sensor_mps[2];
    s = filter_.update(survey_.dvl, r, z, survey_.R_dvl);
  } else if (const auto* att = std::get_if<daemon::Attitude>(&m)) {
    core::MeasVec rp(2), h(1);
    rp << att->roll_rad, att->pitch_rad;
    h << att->heading_rad;
    s = filter_.update(survey_.attitude, r, rp, survey_.R_attitude);
    if (s.ok()) s = filter_.update(survey_.heading, r, h, survey_.R_heading);
  } else if (const auto* depth = std::get_if<daemon::Depth>(&m)) {
    core::MeasVec z(1);
    z << depth->depth_m;
    s = filter_.update(survey_.depth, r, z, survey_.R_depth);
  } else {
    return;  // rates and altitude: not simulated
  }
  if (s.ok()) {
    ++counters_.updates;
  } else {
    ++counters_.update_failures;
    spdlog::warn("navd filter: update at step {} rejected: {}", next_step_, s.to_string());
  }
}

void FilterLoop::apply_links(const core::sim::SurveyStep& step) {
  for (const core::sim::CameraLink& link : step.links) {
    const int a = image_blocks_[static_cast<size_t>(link.image_a)];
    const int b = image_blocks_[static_cast<size_t>(link.image_b)];
    if (a < 0 || b < 0) continue;  // an image event was not received
    core::Status s = filter_.update(survey_.camera, a, b, link.z, survey_.R_camera);
    if (s.ok()) {
      ++counters_.camera_links;
    } else {
      ++counters_.update_failures;
      spdlog::warn("navd filter: camera link {}-{} rejected: {}", link.image_a, link.image_b,
                   s.to_string());
    }
  }
}

void FilterLoop::finish_step() {
  apply_links(survey_.steps[next_step_ - 1]);
  relinearise_robot();
  step_open_ = false;
  ++counters_.steps;
  FilterSnapshot snapshot;
  snapshot.step = counters_.steps;
  snapshot.lambda = filter_.information();
  snapshot.eta = filter_.information_vector();
  snapshot.filter_robot_mean = filter_.mean_block(core::Esdf::kRobotBlock);
  inbox_.post(std::move(records_), std::move(snapshot));
  records_.clear();
  publish_view();
}

void FilterLoop::relinearise_robot() {
  const core::InformationMatrix& info = filter_.information();
  const int r = core::Esdf::kRobotBlock;
  core::Vec12 b = filter_.information_vector().head<12>();
  for (int k = 0; k < info.num_neighbours(r); ++k) {
    b.noalias() -= info.neighbour_block(r, k) * filter_.mean_block(info.neighbour(r, k));
  }
  const Eigen::LLT<core::Mat12> llt(core::Mat12(info.diagonal_block(r)));
  if (llt.info() != Eigen::Success) return;
  core::Vec12 robot = llt.solve(b);
  for (int i = 3; i < 6; ++i) robot(i) = core::wrap_angle(robot(i));
  if (!robot.allFinite()) return;
  Eigen::VectorXd mean = filter_.mean();
  mean.head<12>() = robot;
  if (core::Status s = filter_.set_mean(mean); !s.ok()) fail("relinearise robot", s);
}

void FilterLoop::apply_recovery() {
  RecoveredState rec;
  if (!outbox_.take_new(rec)) return;
  last_residual_ = rec.relative_residual;
  last_iterations_ = rec.iterations;
  if (!rec.ok || rec.mean.size() > filter_.mean().size()) return;
  Eigen::VectorXd mean = filter_.mean();
  const Eigen::Index n = rec.mean.size();
  mean.segment(12, n - 12) = rec.mean.segment(12, n - 12);
  if (filter_.set_mean(mean).ok()) ++counters_.recoveries_applied;
}

void FilterLoop::publish_view() {
  const core::Vec12 robot = filter_.mean_block(core::Esdf::kRobotBlock);
  const std::string line = status_line();
  board_.modify([&](SolutionView& v) {
    v.time_of_validity_us = step_start_us_[next_step_];
    v.robot_mean = robot;
    v.num_delayed_states = filter_.num_blocks() - 1;
    v.num_camera_links = static_cast<int>(counters_.camera_links);
    v.filter_status = counters_.update_failures > 0 ? 1 : 0;
    v.status_line = line;
    v.has_estimate = true;
  });
}

void FilterLoop::notify_systemd(bool force_status) {
  const std::int64_t now = monotonic_us();
  const auto period = notifier_.watchdog_period();
  if (period && now - last_watchdog_us_ >= period->count()) {
    notifier_.watchdog();
    last_watchdog_us_ = now;
  }
  if (force_status || now - last_status_us_ >= kStatusPeriodUs) {
    notifier_.status(status_line());
    last_status_us_ = now;
  }
}

std::string FilterLoop::status_line() const {
  char line[256];
  std::snprintf(
      line, sizeof line, "step %zu/%zu images %llu links %llu queue %zu/%zu drops %llu cg_res %.2e",
      next_step_, survey_.steps.size(), static_cast<unsigned long long>(counters_.images),
      static_cast<unsigned long long>(counters_.camera_links), queue_.size(), queue_.capacity(),
      static_cast<unsigned long long>(queue_.total_dropped()), last_residual_);
  return line;
}

void FilterLoop::fail(const std::string& where, const core::Status& s) {
  error_ = where + ": " + s.to_string();
  spdlog::error("navd filter: {}", error_);
}

FilterLoopResult FilterLoop::finish(bool completed) {
  FilterLoopResult result;
  result.counters = counters_;
  result.ordering = ordering_.stats();
  result.completed = completed;
  result.error = error_;
  result.survey_time_s = static_cast<double>(step_start_us_[next_step_]) * 1e-6;
  if (filter_.initialized()) {
    result.final_position_error_running_m =
        position_error_m(survey_, next_step_, filter_.mean().head<12>());
    if (filter_.recover_mean_direct().ok()) {
      result.final_position_error_m =
          position_error_m(survey_, next_step_, filter_.mean().head<12>());
    }
  }
  notify_systemd(true);
  return result;
}

}  // namespace nav::navd
