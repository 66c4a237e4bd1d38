// The robot alone in covariance form (navigation/dead_reckoning.h).
#include "nav/core/navigation/dead_reckoning.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>
#include <string>

#include "nav/core/navigation/robot_prediction.h"

namespace nav::core {
namespace {

Status error(StatusCode code, const std::string& what) {
  return Status::Error(code, "DeadReckoningFilter: " + what);
}

}  // namespace

DeadReckoningFilter::DeadReckoningFilter(const NavFilterOptions& options)
    : options_(validated(options)),
      sensors_(options_.sensors),
      process_(options_.process_noise),
      aid_gate_(options_.aid_gate) {}

Status DeadReckoningFilter::process(const Measurement& m) {
  ++counters_.measurements;
  if (!initialised_) return try_initialise(m);
  const std::int64_t t_us = validity_us(m);
  if (t_us < last_validity_us_) {
    ++counters_.out_of_order;
    return Status::Ok();
  }
  last_validity_us_ = t_us;
  const Status advanced = advance_to_measurement(time_us_, t_us, options_.min_predict_step_s,
                                                 options_.max_predict_step_s,
                                                 [this](double dt_s) { return predict(dt_s); });
  if (!advanced.ok()) return advanced;
  if (const auto* image = std::get_if<ImageEvent>(&m)) {
    ++counters_.images;
    ImageRecord& record = images_.emplace_back();
    record.t_us = image->time.validity_us;
    record.frame_id = image->frame_id;
    record.robot_mean = x_;
    record.robot_covariance = P_;
    return Status::Ok();
  }
  update_robot(m);
  return Status::Ok();
}

Status DeadReckoningFilter::try_initialise(const Measurement& m) {
  if (!init_.hold(m, sensors_)) ++counters_.before_initialisation;
  if (!init_.ready()) return Status::Ok();
  const RobotPrior prior = initial_robot_prior(init_, sensors_, options_);
  x_ = prior.x0;
  P_ = prior.P0;
  initialised_ = true;
  time_us_ = last_validity_us_ = init_.first_time_us;
  return init_.replay(counters_.measurements, [this](const Measurement& h) { return process(h); });
}

Status DeadReckoningFilter::predict(double dt_s) {
  RobotPrediction p;
  try {
    p = predict_robot(process_, x_, dt_s, options_.initial_rate_sigma_radps);
  } catch (const std::exception& e) {
    return error(StatusCode::kOutOfRange,
                 "prediction at t = " + std::to_string(time_us_) + " us: " + e.what());
  }
  if (!p.held_reason.empty()) ++counters_.predictions_held;
  x_ = p.x_next;
  P_ = p.F * P_ * p.F.transpose() + p.Q;
  P_ = 0.5 * (P_ + P_.transpose()).eval();
  ++counters_.predictions;
  return Status::Ok();
}

template <class Model>
void DeadReckoningFilter::fuse(const AidObservation<Model>& aid) {
  MeasJac H;
  const MeasVec h = aid.model.predict(x_, &H);
  const InnovationSample innovation = innovation_sample(aid.model, aid.z, h, H, P_, aid.R);
  const AidGateDecision gate =
      aid_gate_.decide(aid.sensor, aid.gate_kind, time_us_, innovation.nu, H, aid.R, P_,
                       innovation.valid ? innovation.nis : -1.0);
  const Eigen::LLT<MeasCov> S(innovation.S);
  const bool fused = gate.fuse && innovation.nu.allFinite() && S.info() == Eigen::Success;
  innovations_.record(sensors_, aid.sensor, aid.kind, time_us_, aid.z, aid.R, innovation, fused,
                      gate.reset, gate.gate_sigma);
  if (!gate.fuse) return;
  if (!fused) {
    ++counters_.update_failures;
    return;
  }
  // K = P Hᵀ S⁻¹, from S K ᵀ = H P (S and P symmetric).
  const Eigen::Matrix<double, Eigen::Dynamic, 12, 0, kMaxMeasDim, 12> HP = H * P_;
  const Eigen::Matrix<double, 12, Eigen::Dynamic, 0, 12, kMaxMeasDim> K = S.solve(HP).transpose();
  x_ += K * innovation.nu;
  const Mat12 I_KH = Mat12::Identity() - K * H;
  P_ = I_KH * P_ * I_KH.transpose() + K * aid.R * K.transpose();
  ++counters_.updates;
}

void DeadReckoningFilter::update_robot(const Measurement& m) {
  try {
    if (!for_each_aid(sensors_, m, [this](const auto& aid) { fuse(aid); })) {
      ++counters_.unused;  // altitude and angular rates: not in the robot's models
    }
  } catch (const std::out_of_range&) {
    ++counters_.update_failures;  // a sensor index outside the sensors
  }
}

}  // namespace nav::core
