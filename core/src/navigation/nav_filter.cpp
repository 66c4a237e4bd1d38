// NavFilter: initialisation, prediction, robot updates and images (navigation/nav_filter.h).
// Links: nav_filter_links.cpp; recovery: nav_filter_recovery.cpp.
#include "nav/core/navigation/nav_filter.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "nav/core/geometry/rotation.h"
#include "nav/core/navigation/chi_square.h"
#include "nav/core/navigation/robot_prediction.h"

namespace nav::core {
namespace {

Status error(StatusCode code, const std::string& what) {
  return Status::Error(code, "NavFilter: " + what);
}

/// The filter's own StateRecovery: with a recovery executor it only evaluates the residual of
/// the extended warm start (0 PCG iterations, the certificate of bounds.h); the iterations run
/// as the executor's jobs.
StateRecoveryOptions filter_thread_recovery(const NavFilterOptions& options) {
  if (!options.recovery_thread) return options.recovery;
  StateRecoveryOptions o = options.recovery;
  o.mode = RecoveryMode::kFixedIterations;
  o.iterations_per_step = 0;
  o.preconditioner = RecoveryPreconditioner::kBlockJacobi;  // no factorisation on this thread
  o.renewal_lag = 0;
  return o;
}

/// The recovery jobs' schedule: none without recovery_thread. The job's iterate is certified
/// by the filter on its current Λ at the next image (true residual there), so the job skips its
/// own final residual product.
RecoverySchedule make_schedule(const NavFilterOptions& o) {
  if (!o.recovery_thread) return {};
  StateRecoveryOptions job = o.recovery;
  job.recompute_true_residual = false;
  job.renewal_lag = 0;  // the job is already beside the filter; its renewals go with its result
  std::unique_ptr<RecoveryExecutor> executor =
      o.recovery_executor ? o.recovery_executor(12, job)
                          : std::make_unique<InlineRecoveryExecutor>(12, job);
  return RecoverySchedule(std::move(executor), o.recovery_handoff_s);
}

Vec6 camera_mount(const SensorModels& sensors) {
  return sensors.camera() ? sensors.camera()->x_body_camera : Vec6::Zero();
}

/// Footprint half extents per metre of altitude, (cx/fx, cy/fy), of the first camera (as
/// SensorModels picks it; zero without a camera).
Eigen::Vector2d footprint_half_extent_per_altitude(const std::vector<SensorModelOptions>& sensors) {
  for (const SensorModelOptions& s : sensors) {
    if (s.camera && s.camera->fx_px > 0.0 && s.camera->fy_px > 0.0) {
      return {s.camera->cx_px / s.camera->fx_px, s.camera->cy_px / s.camera->fy_px};
    }
  }
  return Eigen::Vector2d::Zero();
}

}  // namespace

const char* to_string(LinkOutcome outcome) {
  switch (outcome) {
    case LinkOutcome::kAccepted:
      return "accepted";
    case LinkOutcome::kGated:
      return "gated";
    case LinkOutcome::kRegistrationFailed:
      return "registration_failed";
    case LinkOutcome::kNotRegistered:
      return "not_registered";
  }
  return "unknown";
}

NavFilter::NavFilter(NavFilterOptions options, const RegistrationTable* registrations)
    : options_(validated(std::move(options))),
      sensors_(options_.sensors),
      registrations_(registrations),
      process_(options_.process_noise),
      recovery_(12, filter_thread_recovery(options_)),
      bounds_(12, options_.bounds),
      jobs_(make_schedule(options_)),
      proposer_(options_.proposal, footprint_half_extent_per_altitude(options_.sensors),
                camera_mount(sensors_)),
      gate_(options_.camera_gate_chi2, options_.warn),
      aid_gate_(options_.aid_gate),
      pending_(options_.registration_wait_s, options_.max_pending_registrations),
      altitude_m_(options_.default_altitude_m) {
  image_of_block_.push_back(-1);
  warm_.record_steps = jobs_.enabled();
  recovery_.set_renewal_launcher(options_.renewal_launcher);
}

void NavFilter::restore_map(Esdf filter, CovarianceBounds bounds, StateRecovery recovery) {
  filter_ = std::move(filter);
  bounds_ = std::move(bounds);
  recovery_ = std::move(recovery);
  recovery_.set_renewal_launcher(options_.renewal_launcher);
}

std::string NavFilter::index_error() const {
  const long images = static_cast<long>(images_.size());
  const int blocks = filter_.num_blocks();
  // One entry per block (the robot's, -1, exists before initialisation too).
  if (image_of_block_.size() > static_cast<std::size_t>(std::max(blocks, 1))) {
    return "block -> image map has " + std::to_string(image_of_block_.size()) + " entries for " +
           std::to_string(blocks) + " blocks";
  }
  for (long i : image_of_block_) {
    if (i < -1 || i >= images) return "block -> image map names image " + std::to_string(i);
  }
  if (pending_image_ < -1 || pending_image_ >= images) {
    return "pending image " + std::to_string(pending_image_) + " of " + std::to_string(images);
  }
  for (std::size_t l : pending_links_) {
    if (l >= links_.size()) return "pending link " + std::to_string(l) + " unknown";
  }
  for (const ImageRecord& im : images_) {
    if (im.state < -1 || im.state >= blocks) {
      return "image state " + std::to_string(im.state) + " unknown";
    }
  }
  for (const LinkRecord& l : links_) {
    if (l.state_i < -1 || l.state_j < -1 || l.state_i >= blocks || l.state_j >= blocks) {
      return "link state unknown";
    }
  }
  if (warm_.kept < -1 || warm_.kept >= blocks) return "kept block unknown";
  if (init_.roll_pitch_sensor >= sensors_.num_sensors() ||
      init_.heading_sensor >= sensors_.num_sensors()) {
    return "initialisation sensor index unknown";
  }
  return {};
}

void NavFilter::warn(const std::string& message) const {
  if (options_.warn) options_.warn(message);
}

Mat12 NavFilter::robot_covariance() const {
  const Eigen::MatrixXd& bound = bounds_.robot_bound();
  return bound.rows() == 12 && bound.cols() == 12 ? Mat12(bound) : Mat12::Zero();
}

const ImageRecord* NavFilter::image_of_state(int block) const {
  if (block <= 0 || static_cast<std::size_t>(block) >= image_of_block_.size()) return nullptr;
  const long i = image_of_block_[static_cast<std::size_t>(block)];
  return i < 0 ? nullptr : &images_[static_cast<std::size_t>(i)];
}

Status NavFilter::process(const Measurement& m) {
  ++counters_.measurements;
  const std::int64_t t_us = validity_us(m);
  if (!initialised_) return try_initialise(m);
  if (t_us < last_validity_us_) {
    ++counters_.out_of_order;
    return Status::Ok();
  }
  last_validity_us_ = t_us;
  now_realtime_us_ = time_of(m).host_realtime_us;
  if (jobs_.due(t_us)) take_recovery_result();  // hand-off at a data time
  // Less than min_predict_step_s after the filter's time: applied at that time (a very short
  // prediction makes Q's pose block tiny and Λ ill-conditioned).
  const Status advanced = advance_to_measurement(
      time_us_, t_us, options_.min_predict_step_s, options_.max_predict_step_s,
      [this](double dt_s) { return predict_once(dt_s); });
  if (!advanced.ok()) return advanced;
  pending_.resolve_due(registrations_, now_realtime_us_,
                       [this](PendingRegistrations::Entry& e, const RegistrationResult* reg) {
                         finish_pending(e, reg);
                       });
  if (const auto* image = std::get_if<ImageEvent>(&m)) return on_image(*image);
  update_robot(m);
  return Status::Ok();
}

Status NavFilter::try_initialise(const Measurement& m) {
  if (!init_.hold(m, sensors_)) {
    ++counters_.before_initialisation;  // dropped: no attitude/depth for too long
  }
  if (!init_.ready()) return Status::Ok();
  // The world origin is the vehicle at the start of the dive (hil-tests/README.md): start at
  // the first measurement's time and replay everything held so far through the filter.
  if (Status s = initialise(init_.first_time_us); !s.ok()) return s;
  return init_.replay(counters_.measurements, [this](const Measurement& h) { return process(h); });
}

Status NavFilter::initialise(std::int64_t t_us) {
  const RobotPrior prior = initial_robot_prior(init_, sensors_, options_);
  if (Status s = filter_.initialize(prior.x0, prior.P0); !s.ok()) return s;
  if (Status s = bounds_.initialize_robot(prior.P0); !s.ok()) return s;
  if (Status s = recovery_.initialize(prior.x0, prior.P0); !s.ok()) return s;
  warm_.restart(prior.P0);
  initialised_ = true;
  time_us_ = t_us;
  last_validity_us_ = t_us;
  return Status::Ok();
}

Status NavFilter::predict_once(double dt_s) {
  relinearise_robot();
  RobotPrediction p;
  try {
    p = predict_robot(process_, filter_.mean_block(Esdf::kRobotBlock), dt_s,
                      options_.initial_rate_sigma_radps);
  } catch (const std::exception& e) {
    return error(StatusCode::kOutOfRange,
                 "prediction at t = " + std::to_string(time_us_) + " us: " + e.what());
  }
  if (!p.held_reason.empty()) {
    // Pitch off the model's branch: a held step with the attitude and rates treated as lost
    // (robot_prediction.h) instead of ending the filter; counted, warned at the 1st, 2nd, 4th...
    const std::uint64_t n = ++counters_.predictions_held;
    if ((n & (n - 1)) == 0) {
      warn("NavFilter: prediction at t = " + std::to_string(time_us_) + " us held (" +
           std::to_string(n) + " so far): " + p.held_reason);
    }
  }
  const bool keep = pending_image_ >= 0;
  int kept = -1;  // the block keeping the pending image
  if (Status s = filter_.predict(p.x_next, p.F, p.Q, keep, &kept); !s.ok()) return s;
  if (Status s = bounds_.predict_robot(p.F, p.Q, keep, kept); !s.ok()) return s;
  ++counters_.predictions;
  warm_.predicted_with(p.F, p.Q, keep ? kept : -1);
  if (keep) {
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
    if (jobs_.enabled()) submit_recovery_job();
  }
  return Status::Ok();
}

std::optional<Vec12> NavFilter::conditional_robot_mean() const {
  const InformationMatrix& info = filter_.information();
  const int r = Esdf::kRobotBlock;
  Vec12 b = filter_.information_vector().head<12>();
  for (int k = 0; k < info.num_neighbours(r); ++k) {
    b.noalias() -= info.neighbour_block(r, k) * filter_.mean_block(info.neighbour(r, k));
  }
  const Eigen::LLT<Mat12> llt(Mat12(info.diagonal_block(r)));
  if (llt.info() != Eigen::Success) return std::nullopt;
  const Vec12 robot = llt.solve(b);
  if (!robot.allFinite()) return std::nullopt;
  return robot;
}

void NavFilter::relinearise_robot() {
  // Not wrapped: the angles of the mean must stay on the branch η encodes. Wrapping only μ_r
  // (η_r unchanged) shifts the next update's η_r += Hᵀ R⁻¹ (ν + H μ_r) by 2π·Hᵀ R⁻¹ H on a
  // heading that crossed ±π, which moved the whole map 5.4 m in one turn of the default dive.
  if (const std::optional<Vec12> robot = conditional_robot_mean()) {
    (void)filter_.set_mean_block(Esdf::kRobotBlock, *robot);
  }
}

Vec12 NavFilter::robot_mean() const {
  if (!initialised_) return Vec12::Zero();
  return conditional_robot_mean().value_or(Vec12(filter_.mean_block(Esdf::kRobotBlock)));
}

template <class Model>
void NavFilter::fuse(const AidObservation<Model>& aid) {
  const int r = Esdf::kRobotBlock;
  MeasJac H;
  const MeasVec h = aid.model.predict(filter_.mean_block(r), &H);  // as the update below
  const InnovationSample innovation = innovation_sample(aid.model, aid.z, h, H, warm_.P, aid.R);
  const AidGateDecision gate =
      aid_gate_.decide(aid.sensor, aid.gate_kind, time_us_, innovation.nu, H, aid.R, warm_.P,
                       innovation.valid ? innovation.nis : -1.0);
  if (gate.run_started || gate.reset_started) {
    warn(std::string("NavFilter: ") + aid.kind + " from sensor '" + sensors_.name(aid.sensor) +
         "' at t = " + std::to_string(time_us_) + " us " +
         (gate.reset_started ? "fused again after its reset timeout" : "gated") + ": test ratio " +
         std::to_string(gate.test_ratio) + " (further ones counted in its rejected updates)");
  }
  if (!gate.fuse) {
    innovations_.record(sensors_, aid.sensor, aid.kind, time_us_, aid.z, aid.R, innovation, false,
                        false, gate.gate_sigma);
    return;
  }
  const Status s = filter_.update(aid.model, r, aid.z, aid.R);
  innovations_.record(sensors_, aid.sensor, aid.kind, time_us_, aid.z, aid.R, innovation, s.ok(),
                      gate.reset, gate.gate_sigma);
  if (s.ok()) {
    ++counters_.updates;
    if (!bounds_.update_robot(H, aid.R).ok()) ++counters_.bound_update_failures;
    warm_.updated_with(H, aid.R);
    return;
  }
  ++counters_.update_failures;
  warn(std::string("NavFilter: ") + aid.kind + " update from sensor '" + sensors_.name(aid.sensor) +
       "' at t = " + std::to_string(time_us_) + " us rejected: " + s.to_string());
}

void NavFilter::update_robot(const Measurement& m) {
  try {
    if (for_each_aid(sensors_, m, [this](const auto& aid) { fuse(aid); })) return;
    if (const auto* alt = std::get_if<Altitude>(&m)) {
      if (alt->altitude_m > 0.0 && std::isfinite(alt->altitude_m)) altitude_m_ = alt->altitude_m;
    }
    ++counters_.unused;  // altitude sets the footprints; angular rates: no rate model
  } catch (const std::out_of_range& e) {
    ++counters_.update_failures;
    warn(std::string("NavFilter: ") + e.what());
  }
}

Status NavFilter::on_image(const ImageEvent& image) {
  if (pending_image_ >= 0) {
    ++counters_.duplicate_images;  // a second image at the same time of validity
    return Status::Ok();
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
    if (before_proposal_) before_proposal_(*this);
    if (options_.propose_links && sensors_.camera()) propose_and_link(current);
  }
  relinearise_robot();
  current.robot_mean = filter_.mean_block(Esdf::kRobotBlock);
  pending_image_ = static_cast<long>(images_.size()) - 1;
  return Status::Ok();
}

Status NavFilter::finish() {
  if (recovery_in_flight()) take_recovery_result();
  pending_.expire_all([this](PendingRegistrations::Entry& e, const RegistrationResult* reg) {
    finish_pending(e, reg);  // never answered
  });
  if (!initialised_ || pending_image_ < 0) return Status::Ok();
  const std::int64_t step_us = 100'000;  // 0.1 s: keeps the last image's state
  if (Status s = predict_once(1e-6 * static_cast<double>(step_us)); !s.ok()) return s;
  time_us_ += step_us;
  if (recovery_in_flight()) take_recovery_result();  // the job of that kept state
  return Status::Ok();
}

}  // namespace nav::core
