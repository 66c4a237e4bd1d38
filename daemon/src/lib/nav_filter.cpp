// NavFilter: initialisation, prediction, robot updates, images and recovery (nav_filter.h).
// Link proposal and gating: nav_filter_links.cpp.
#include "nav/daemon/filter/nav_filter.h"

#include <spdlog/spdlog.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>
#include <string>

#include "nav/core/geometry/rotation.h"
#include "nav/daemon/filter/chi_square.h"

namespace nav::daemon {
namespace {

constexpr double kInitialSigmaFactor = 10.0;

core::Status error(core::StatusCode code, const std::string& what) {
  return core::Status::Error(code, "NavFilter: " + what);
}

/// The filter thread's own StateRecovery: with the recovery thread it only evaluates the
/// residual of the extended warm start (0 PCG iterations, the certificate of bounds.h); the
/// iterations run on the thread.
core::StateRecoveryOptions filter_thread_recovery(const NavFilterOptions& options) {
  if (!options.recovery_thread) return options.recovery;
  core::StateRecoveryOptions o = options.recovery;
  o.mode = core::RecoveryMode::kFixedIterations;
  o.iterations_per_step = 0;
  return o;
}

core::MeasVec vec1(double a) {
  core::MeasVec z(1);
  z << a;
  return z;
}

}  // namespace

NavFilterOptions NavFilterOptions::from_config(const NavdConfig& config) {
  NavFilterOptions o;
  o.recovery.mode = core::RecoveryMode::kFixedIterations;
  o.recovery.iterations_per_step = config.filter.cg_iterations_per_step;
  o.camera_gate_chi2 = equivalent_chi_square_gate(config.filter.gating_chi2_threshold, 6, 5);
  o.recovery_thread = config.filter.recovery_thread;
  o.recovery_handoff_s = config.filter.recovery_handoff_s;
  o.registration_wait_s = config.filter.registration_wait_s;
  o.max_pending_registrations = config.filter.max_pending_registrations;
  return o;
}

const char* to_string(LinkOutcome outcome) {
  switch (outcome) {
    case LinkOutcome::kAccepted: return "accepted";
    case LinkOutcome::kGated: return "gated";
    case LinkOutcome::kRegistrationFailed: return "registration_failed";
    case LinkOutcome::kNotRegistered: return "not_registered";
  }
  return "unknown";
}

NavFilter::NavFilter(const NavdConfig& config, const RegistrationTable* registrations,
                     NavFilterOptions options)
    : options_(options),
      sensors_(config),
      registrations_(registrations),
      process_(config.filter.process_noise),
      recovery_(12, filter_thread_recovery(options)),
      bounds_(12, options.bounds),
      altitude_m_(options.default_altitude_m) {
  if (!(options_.max_predict_step_s > 0.0) ||
      !(options_.min_predict_step_s >= 0.0 && options_.min_predict_step_s < options_.max_predict_step_s) || !(options_.default_altitude_m > 0.0) ||
      !(options_.proposal_confidence > 0.0 && options_.proposal_confidence < 1.0) ||
      !(options_.camera_gate_chi2 > 0.0) || !(options_.initial_xy_sigma_m > 0.0) ||
      !(options_.initial_velocity_sigma_mps > 0.0) || !(options_.initial_rate_sigma_radps > 0.0)) {
    throw std::invalid_argument(
        "NavFilterOptions: max_predict_step_s, default_altitude_m, camera_gate_chi2 and the "
        "initial sigmas must be > 0, proposal_confidence in (0, 1)");
  }
  if (!(options_.recovery_handoff_s >= 0.0 && options_.recovery_handoff_s <= 3600.0)) {
    throw std::invalid_argument("NavFilterOptions: recovery_handoff_s must be in [0, 3600] s, is " +
                                std::to_string(options_.recovery_handoff_s));
  }
  if (!(options_.registration_wait_s >= 0.0 && options_.registration_wait_s <= 3600.0) ||
      options_.max_pending_registrations < 1 || options_.max_pending_registrations > 100000) {
    throw std::invalid_argument(
        "NavFilterOptions: registration_wait_s must be in [0, 3600] s (is " +
        std::to_string(options_.registration_wait_s) + "), max_pending_registrations in [1, " +
        "100000] (is " + std::to_string(options_.max_pending_registrations) + ")");
  }
  if (options_.registration_wait_s > 0.0) {
    pending_.reserve(static_cast<std::size_t>(options_.max_pending_registrations));
  }
  if (options_.recovery_thread) {
    // The job's iterate is certified by the filter on its current Λ at the next image (true
    // residual there), so the job skips its own final residual product.
    core::StateRecoveryOptions job = options_.recovery;
    job.recompute_true_residual = false;
    worker_.worker = std::make_unique<RecoveryWorker>(12, job, options_.recovery_test_hook,
                                                      !options_.recovery_inline);
  }
  proposal_chi2_ = chi_square_quantile(options_.proposal_confidence, 2);
  image_of_block_.push_back(-1);
}

const ImageRecord* NavFilter::image_of_state(int block) const {
  if (block <= 0 || static_cast<std::size_t>(block) >= image_of_block_.size()) return nullptr;
  const long i = image_of_block_[static_cast<std::size_t>(block)];
  return i < 0 ? nullptr : &images_[static_cast<std::size_t>(i)];
}

core::Status NavFilter::process(const Measurement& m) {
  ++counters_.measurements;
  const std::int64_t t_us = validity_us(m);
  if (!initialised_) return try_initialise(m);
  if (t_us < last_validity_us_) {
    ++counters_.out_of_order;
    return core::Status::Ok();
  }
  last_validity_us_ = t_us;
  now_realtime_us_ = time_of(m).host_realtime_us;
  // The recovery thread's result is taken at a data time (nav_filter.h "Recovery thread").
  if (recovery_in_flight() && t_us >= handoff_us_) take_recovery_result();
  // Measurements less than min_predict_step_s after the filter's time are applied at that time
  // (nav_filter.h: a very short prediction makes Q's pose block tiny and Λ ill-conditioned).
  const auto min_step_us = static_cast<std::int64_t>(std::llround(options_.min_predict_step_s * 1e6));
  if (t_us - time_us_ >= min_step_us) {
    if (core::Status s = advance_to(t_us); !s.ok()) return s;
  }
  resolve_pending(now_realtime_us_);  // asynchronous registrations (nav_filter_pending.cpp)
  if (const auto* image = std::get_if<ImageEvent>(&m)) return on_image(*image);
  update_robot(m);
  return core::Status::Ok();
}

core::Status NavFilter::try_initialise(const Measurement& m) {
  if (pre_init_.empty()) first_time_us_ = validity_us(m);
  if (pre_init_.size() < kMaxPreInit) {
    pre_init_.push_back(m);
  } else {
    ++counters_.before_initialisation;  // dropped: no attitude/depth for too long
  }
  if (const auto* att = std::get_if<Attitude>(&m)) {
    const BodyAttitude body = sensors_.body_attitude(*att);
    if (body.has_roll_pitch) {
      init_roll_pitch_ = body;
      init_rp_sensor_ = att->time.sensor_index;
    }
    if (body.has_heading) {
      init_heading_ = body;
      init_heading_sensor_ = att->time.sensor_index;
    }
  } else if (const auto* depth = std::get_if<Depth>(&m)) {
    init_depth_ = *depth;
  }
  if (!(init_roll_pitch_ && init_heading_ && init_depth_)) return core::Status::Ok();
  // The world origin is the vehicle at the start of the dive (hil-tests/README.md): start at
  // the first measurement's time and replay everything held so far through the filter.
  if (core::Status s = initialise(first_time_us_); !s.ok()) return s;
  std::vector<Measurement> held;
  held.swap(pre_init_);
  counters_.measurements -= held.size();  // counted again below
  for (const Measurement& h : held) {
    if (core::Status s = process(h); !s.ok()) return s;
  }
  return core::Status::Ok();
}

core::Status NavFilter::initialise(std::int64_t t_us) {
  const std::size_t depth_sensor = init_depth_->time.sensor_index;
  const core::Vec3 rpy(init_roll_pitch_->roll_rad, init_roll_pitch_->pitch_rad,
                       init_heading_->heading_rad);
  const core::Vec3 lever = sensors_.depth(depth_sensor).p_body_sensor_m;
  core::Vec12 x0 = core::Vec12::Zero();
  x0(2) = init_depth_->depth_m - (core::rotation_from_euler(rpy) * lever)(2);
  x0.segment<3>(3) = rpy;
  core::Vec12 sigma;
  sigma << options_.initial_xy_sigma_m, options_.initial_xy_sigma_m,
      std::sqrt(sensors_.depth_noise(depth_sensor)(0, 0)), 0, 0, 0,
      core::Vec3::Constant(options_.initial_velocity_sigma_mps),
      core::Vec3::Constant(options_.initial_rate_sigma_radps);
  // Attitude prior: the attitude sensor's own noise (the first message is a measurement).
  // Attitude and depth priors 10x the sensors' sigmas: the messages they come from are applied
  // again as measurement updates once the held measurements are replayed.
  sigma(2) *= kInitialSigmaFactor;
  sigma(3) = sigma(4) =
      kInitialSigmaFactor * std::sqrt(sensors_.roll_pitch_noise(init_rp_sensor_)(0, 0));
  sigma(5) = kInitialSigmaFactor * std::sqrt(sensors_.heading_noise(init_heading_sensor_)(0, 0));
  const core::Mat12 P0 = sigma.array().square().matrix().asDiagonal();
  if (core::Status s = filter_.initialize(x0, P0); !s.ok()) return s;
  if (core::Status s = bounds_.initialize_robot(P0); !s.ok()) return s;
  if (core::Status s = recovery_.initialize(x0, P0); !s.ok()) return s;
  sigma_tt_ = P0;
  P_robot_ = P0;
  initialised_ = true;
  time_us_ = t_us;
  last_validity_us_ = t_us;
  return core::Status::Ok();
}

core::Status NavFilter::advance_to(std::int64_t t_us) {
  // Equal steps of at most max_predict_step_s (no short remainder step, see min_predict_step_s).
  const auto max_step_us = std::max<std::int64_t>(
      1, static_cast<std::int64_t>(std::llround(options_.max_predict_step_s * 1e6)));
  const std::int64_t gap_us = t_us - time_us_;
  const std::int64_t steps = (gap_us + max_step_us - 1) / max_step_us;
  for (std::int64_t k = 1; k <= steps; ++k) {
    const std::int64_t next_us = time_us_ + (t_us - time_us_) / (steps - k + 1);
    if (core::Status s = predict_once(static_cast<double>(next_us - time_us_) * 1e-6); !s.ok()) {
      return s;
    }
    time_us_ = next_us;
  }
  return core::Status::Ok();
}

core::Status NavFilter::predict_once(double dt_s) {
  relinearise_robot();
  const core::Vec12 x = filter_.mean_block(core::Esdf::kRobotBlock);
  core::Mat12 F;
  core::Vec12 f;
  core::Mat12 Q;
  try {
    f = process_.predict(x, dt_s, &F);
    Q = process_.process_noise(x, dt_s);
  } catch (const std::exception& e) {
    return error(core::StatusCode::kOutOfRange,
                 "prediction at t = " + std::to_string(time_us_) + " us: " + e.what());
  }
  const bool keep = pending_image_ >= 0;
  int kept = -1;
  if (core::Status s = filter_.predict(f, F, Q, keep, &kept); !s.ok()) return s;
  if (core::Status s = bounds_.predict_robot(F, Q, keep, kept); !s.ok()) return s;
  ++counters_.predictions;
  A_since_recovery_ = F * A_since_recovery_;
  P_robot_ = F * P_robot_ * F.transpose() + Q;
  predicted_since_recovery_ = true;
  if (keep) {
    kept_since_recovery_ = kept;
    if (image_of_block_.size() <= static_cast<std::size_t>(kept)) {
      image_of_block_.resize(static_cast<std::size_t>(kept) + 1, -1);
    }
    image_of_block_[static_cast<std::size_t>(kept)] = pending_image_;
    ImageRecord& kept_image = images_[static_cast<std::size_t>(pending_image_)];
    kept_image.state = kept;
    kept_image.initial_bound = bounds_.bound(kept).topLeftCorner(6, 6);
    for (std::size_t row : pending_links_) links_[row].state_j = kept;
    pending_links_.clear();
    pending_image_ = -1;
  }
  return core::Status::Ok();
}

void NavFilter::relinearise_robot() {
  const core::InformationMatrix& info = filter_.information();
  const int r = core::Esdf::kRobotBlock;
  core::Vec12 b = filter_.information_vector().head<12>();
  for (int k = 0; k < info.num_neighbours(r); ++k) {
    b.noalias() -= info.neighbour_block(r, k) * filter_.mean_block(info.neighbour(r, k));
  }
  const Eigen::LLT<core::Mat12> llt(core::Mat12(info.diagonal_block(r)));
  if (llt.info() != Eigen::Success) return;
  // Not wrapped: the angles of the mean must stay on the branch η encodes. Wrapping only μ_r
  // (η_r unchanged) shifts the next update's η_r += Hᵀ R⁻¹ (ν + H μ_r) by 2π·Hᵀ R⁻¹ H on a
  // heading that crossed ±π, which moved the whole map 5.4 m in one turn of the default dive.
  const core::Vec12 robot = llt.solve(b);
  if (robot.allFinite()) (void)filter_.set_mean_block(r, robot);
}

void NavFilter::track_robot_update(const core::MeasJac& H, const core::MeasCov& R) {
  const Eigen::MatrixXd PHt = P_robot_ * H.transpose();
  const Eigen::LLT<Eigen::MatrixXd> llt(H * PHt + R);
  if (llt.info() != Eigen::Success) return;
  const Eigen::MatrixXd K = llt.solve(PHt.transpose()).transpose();
  const core::Mat12 IKH = core::Mat12::Identity() - K * H;
  A_since_recovery_ = IKH * A_since_recovery_;
  P_robot_ = IKH * P_robot_ * IKH.transpose() + K * R * K.transpose();
}

template <class Model>
void NavFilter::update_unary(const Model& model, const core::MeasVec& z, const core::MeasCov& R,
                             const char* what, std::size_t sensor) {
  const int r = core::Esdf::kRobotBlock;
  core::MeasJac H;
  const core::MeasVec h = model.predict(filter_.mean_block(r), &H);  // as the update below
  const InnovationSample innovation = innovation_sample(model, z, h, H, P_robot_, R);
  const core::Status s = filter_.update(model, r, z, R);
  innovations_.record(sensors_, sensor, what, time_us_, z, R, innovation, s.ok());
  if (s.ok()) {
    ++counters_.updates;
    if (!bounds_.update_robot(H, R).ok()) ++counters_.bound_update_failures;
    track_robot_update(H, R);
    return;
  }
  ++counters_.update_failures;
  spdlog::warn("NavFilter: {} update from sensor '{}' at t = {} us rejected: {}", what,
               sensors_.name(sensor), time_us_, s.to_string());
}

void NavFilter::update_robot(const Measurement& m) {
  const std::size_t sensor = time_of(m).sensor_index;
  try {
    if (const auto* dvl = std::get_if<DvlVelocity>(&m)) {
      core::MeasVec z(3);
      z << dvl->v_sensor_mps[0], dvl->v_sensor_mps[1], dvl->v_sensor_mps[2];
      update_unary(sensors_.dvl(sensor), z, sensors_.dvl_noise(sensor), "DVL", sensor);
    } else if (const auto* att = std::get_if<Attitude>(&m)) {
      const BodyAttitude body = sensors_.body_attitude(*att);
      if (body.has_roll_pitch) {
        core::MeasVec z(2);
        z << body.roll_rad, body.pitch_rad;
        update_unary(core::AttitudeModel{}, z, sensors_.roll_pitch_noise(sensor), "roll/pitch",
                     sensor);
      }
      if (body.has_heading) {
        update_unary(core::HeadingModel{}, vec1(body.heading_rad), sensors_.heading_noise(sensor),
                     "heading", sensor);
      }
    } else if (const auto* depth = std::get_if<Depth>(&m)) {
      update_unary(sensors_.depth(sensor), vec1(depth->depth_m), sensors_.depth_noise(sensor),
                   "depth", sensor);
    } else if (const auto* alt = std::get_if<Altitude>(&m)) {
      if (alt->altitude_m > 0.0 && std::isfinite(alt->altitude_m)) altitude_m_ = alt->altitude_m;
      ++counters_.unused;
    } else {
      ++counters_.unused;  // angular rates: no rate model in the filter
    }
  } catch (const std::out_of_range& e) {
    ++counters_.update_failures;
    spdlog::warn("NavFilter: {}", e.what());
  }
}

core::Status NavFilter::on_image(const ImageEvent& image) {
  if (pending_image_ >= 0) {
    ++counters_.duplicate_images;  // a second image at the same time of validity
    return core::Status::Ok();
  }
  ++counters_.images;
  ImageRecord record;
  record.t_us = image.time.validity_us;
  record.frame_id = image.frame_id;
  record.altitude_m = altitude_m_;
  images_.push_back(record);
  ImageRecord& current = images_.back();
  const bool recovered = recover();
  current.relative_residual = last_relative_residual_;
  if (recovered) {
    current.robot_covariance = recovery_.robot_covariance();
    if (options_.propose_links && sensors_.camera()) propose_and_link(current);
  }
  relinearise_robot();
  current.robot_mean = filter_.mean_block(core::Esdf::kRobotBlock);
  pending_image_ = static_cast<long>(images_.size()) - 1;
  if (worker_.worker) submit_recovery_job();
  return core::Status::Ok();
}

core::Status NavFilter::finish() {
  if (recovery_in_flight()) take_recovery_result();
  for (Pending& p : pending_) finish_pending(p, nullptr);  // never answered
  pending_.clear();
  if (!initialised_ || pending_image_ < 0) return core::Status::Ok();
  const std::int64_t step_us = 100'000;  // 0.1 s: keeps the last image's state
  if (core::Status s = predict_once(1e-6 * static_cast<double>(step_us)); !s.ok()) return s;
  time_us_ += step_us;
  return core::Status::Ok();
}

}  // namespace nav::daemon
