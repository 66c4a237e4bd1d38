#pragma once
// DeadReckoningFilter: the robot alone, in covariance form: the baseline that "SLAM against
// dead reckoning" is measured against (docs/consistency.md "The dead-reckoning baseline").
//
// It fuses what NavFilter fuses except camera links, with the same models, steps, prior and
// innovation gates (robot_prediction.h, initial_state.h, aid_sources.h, aid_gate.h), as an
// extended Kalman filter of the 12-element robot state (Bar-Shalom, Li & Kirubarajan 2001,
// §10.3): predict x ← f(x), P ← F P Fᵀ + Q; update K = P Hᵀ S⁻¹, x ← x + K ν,
// P ← (I − K H) P (I − K H)ᵀ + K R Kᵀ (Joseph form), each aid linearised at the mean its
// update sees. In exact arithmetic its robot is NavFilter's robot without links (a delayed
// state without links does not change the robot's marginal). In floating point the information
// form loses digits at every prediction step of a few milliseconds (Q⁻¹ ~ dt⁻³ cancels in the
// marginalisation of the old robot), and a chain of hundreds of delayed states with no link to
// tie it carries them into its means, which a change of one measurement at the rounding level
// then moves by decimetres; this filter's track moves by rounding only (docs/consistency.md
// "The dead-reckoning baseline"): it is a property of the sensors.
//
// Contract: measurements in time-of-validity order (an older one is counted out_of_order and
// skipped); O(1) per measurement, plus one record per image; not thread-safe.
#include <cstdint>
#include <vector>

#include "nav/core/models/constant_velocity.h"
#include "nav/core/navigation/aid_gate.h"
#include "nav/core/navigation/aid_sources.h"
#include "nav/core/navigation/initial_state.h"
#include "nav/core/navigation/innovation_stats.h"
#include "nav/core/navigation/nav_filter_options.h"
#include "nav/core/navigation/nav_filter_records.h"
#include "nav/core/navigation/sensor_measurements.h"
#include "nav/core/navigation/sensor_models.h"
#include "nav/core/status.h"

namespace nav::core {

class DeadReckoningFilter {
 public:
  /// Uses the sensors, process noise, prior sigmas, prediction steps and aid gates of `options`
  /// (validated as NavFilter validates them: std::invalid_argument otherwise).
  explicit DeadReckoningFilter(const NavFilterOptions& options);

  /// Processes one measurement: predicts to its time, then fuses it (an aid) or records the
  /// estimate (an image). An error only when the prediction fails.
  Status process(const Measurement& m);

  bool initialised() const { return initialised_; }
  std::int64_t time_us() const { return time_us_; }
  const Vec12& robot_mean() const { return x_; }
  const Mat12& robot_covariance() const { return P_; }
  /// One record per image: time, frame, the robot's mean and covariance at it (state, links
  /// and bounds unused).
  const std::vector<ImageRecord>& images() const { return images_; }
  const NavFilterCounters& counters() const { return counters_; }
  const SensorInnovationStats& innovations() const { return innovations_; }

 private:
  Status try_initialise(const Measurement& m);
  Status predict(double dt_s);
  void update_robot(const Measurement& m);
  template <class Model>
  void fuse(const AidObservation<Model>& aid);

  NavFilterOptions options_;
  SensorModels sensors_;
  ConstantVelocityModel process_;
  AidGate aid_gate_;
  HeldInitialisation init_;
  bool initialised_ = false;
  std::int64_t time_us_ = 0;
  std::int64_t last_validity_us_ = 0;
  Vec12 x_ = Vec12::Zero();
  Mat12 P_ = Mat12::Zero();
  std::vector<ImageRecord> images_;
  NavFilterCounters counters_;
  SensorInnovationStats innovations_;
};

}  // namespace nav::core
