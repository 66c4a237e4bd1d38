// The robot's time update shared by both filters (navigation/robot_prediction.h).
#include "nav/core/navigation/robot_prediction.h"

#include <numbers>
#include <stdexcept>

#include "nav/core/navigation/held_prediction.h"

namespace nav::core {
namespace {
/// Attitude sigma added by a held prediction step (held_prediction.h): half a turn, i.e. lost.
constexpr double kLostAttitudeSigmaRad = std::numbers::pi;
}  // namespace

RobotPrediction predict_robot(const ConstantVelocityModel& process, const Vec12& x, double dt_s,
                              double lost_rate_sigma_radps) {
  RobotPrediction p;
  try {
    p.f = process.predict(x, dt_s, &p.F);
    p.Q = process.process_noise(x, dt_s);
  } catch (const std::domain_error& e) {
    const HeldPrediction held =
        held_prediction(x, dt_s, process.options(), kLostAttitudeSigmaRad, lost_rate_sigma_radps);
    p.f = held.x_next;
    p.F = held.F;
    p.Q = held.Q;
    p.held_reason = e.what();
  }
  return p;
}

}  // namespace nav::core
