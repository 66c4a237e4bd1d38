#pragma once
// The robot's time update, shared by NavFilter (information form, nav_filter.h) and
// DeadReckoningFilter (covariance form, dead_reckoning.h): the same model and the same steps, so
// the two estimate the same thing and differ only in the form they keep it in.
// * predict_robot: the constant-velocity model at the mean (constant_velocity.h), or the held
//   step where the model cannot take it (pitch off its branch: held_prediction.h).
// * advance_in_steps: a gap predicted in equal steps of at most max_step_s, with no short
//   remainder step (a very short step makes Q's pose block tiny).
#include <cstdint>
#include <string>

#include "nav/core/geometry/types.h"
#include "nav/core/models/constant_velocity.h"
#include "nav/core/status.h"

namespace nav::core {

/// x_{t+dt} ≈ f + F (x − x̄), with process noise Q.
struct RobotPrediction {
  Vec12 f = Vec12::Zero();
  Mat12 F = Mat12::Identity();
  Mat12 Q = Mat12::Zero();
  std::string held_reason;  ///< why the model's step was held ("": the model's step)
};

/// The model's step from x over dt_s > 0, or the held step (attitude lost: sigma π, rates
/// restarted with lost_rate_sigma_radps) when the model throws std::domain_error. Other
/// exceptions (an invalid dt) propagate.
RobotPrediction predict_robot(const ConstantVelocityModel& process, const Vec12& x, double dt_s,
                              double lost_rate_sigma_radps);

/// Advances time_us to t_us in ceil(gap / max_step) equal steps, calling step(dt_s) for each
/// and moving time_us after each success; returns the first failing step's status.
template <class Step>
Status advance_in_steps(std::int64_t& time_us, std::int64_t t_us, double max_step_s, Step&& step);

}  // namespace nav::core

#include <algorithm>
#include <cmath>

namespace nav::core {

template <class Step>
Status advance_in_steps(std::int64_t& time_us, std::int64_t t_us, double max_step_s, Step&& step) {
  const auto max_step_us =
      std::max<std::int64_t>(1, static_cast<std::int64_t>(std::llround(max_step_s * 1e6)));
  const std::int64_t steps = (t_us - time_us + max_step_us - 1) / max_step_us;
  for (std::int64_t k = 1; k <= steps; ++k) {
    const std::int64_t next_us = time_us + (t_us - time_us) / (steps - k + 1);
    if (Status s = step(static_cast<double>(next_us - time_us) * 1e-6); !s.ok()) return s;
    time_us = next_us;
  }
  return Status::Ok();
}

}  // namespace nav::core
