#pragma once
// Innovation monitoring of NavFilter's unary (robot) updates, per sensor: the uniform status of
// each aid source (aid_sources.h), the record PX4 EKF2 keeps per fused measurement
// (msg/EstimatorAidSource1d.msg: observation, variance, innovation, innovation variance, test
// ratio, rejected / fused); navd publishes it in health_t.
//
// For an update z with model h, Jacobian H at the robot mean μ_r and noise R:
//   ν = z − h(μ_r) (angle rows wrapped),   S = H P Hᵀ + R,   NIS = νᵀ S⁻¹ ν,
// with P the robot covariance NavFilter tracks between recoveries (warm_start_tracker.h: the
// recovered Σ_rr carried through the robot's own predictions and updates; camera links since the
// last recovery are not in it, so P can only be larger than Σ_rr and the NIS smaller). For a
// consistent filter NIS ~ chi²(dim z): its mean is dim z (Bar-Shalom, Li & Kirubarajan 2001, §5.4).
// A biased or mis-modelled sensor shows a mean NIS far above its dimension. Per component k: test
// ratio ν_k² / (g² S_kk) with g the update's gate in sigmas (aid_gate.h; kTestRatioGateSigma = 3
// when its gate is off): > 1 beyond the gate.
//
// Counters are cumulative (never reset): a reader takes the mean over its own period from two
// snapshots (innovation_period). Owned by NavFilter's thread; a sensor's slot is created (with
// its name) at its first update, after that recording does not allocate.

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "nav/core/geometry/types.h"
#include "nav/core/models/measurement.h"
#include "nav/core/navigation/sensor_models.h"

namespace nav::core {

inline constexpr double kTestRatioGateSigma = 3.0;
inline constexpr int kMaxInnovationComponents = 6;

/// The innovation of one update before it is applied.
struct InnovationSample {
  MeasVec nu;          ///< z − h(μ), angles wrapped
  MeasCov S;           ///< H P Hᵀ + R
  double nis = 0.0;    ///< νᵀ S⁻¹ ν (0 when !valid)
  bool valid = false;  ///< S positive definite and ν finite
};

/// One component of the last update (aid_source_t).
struct InnovationComponent {
  std::int64_t time_of_validity_us = 0;
  double observation = 0.0, observation_variance = 0.0;
  double innovation = 0.0, innovation_variance = 0.0;
  double test_ratio = 0.0;
  bool fused = false;
};

/// Cumulative innovation record of one sensor.
struct SensorInnovation {
  std::size_t sensor = 0;         ///< NavFilterOptions::sensors index
  std::string name;               ///< its SensorModelOptions::name
  std::uint64_t updates = 0;      ///< updates applied (fused)
  std::uint64_t rejected = 0;     ///< updates not fused: gated (aid_gate.h) or refused by the ESDF
  std::uint64_t gate_resets = 0;  ///< of the fused: fused by the gate's timeout reset
  std::uint64_t nis_count = 0;    ///< updates (fused or not) with a valid NIS (summed below)
  double nis_sum = 0.0;           ///< Σ NIS over those
  double dim_sum = 0.0;           ///< Σ dim z over those (the NIS sum's expected value)
  double nis_last = -1.0;         ///< of the last update (-1: none valid yet)
  int dim_last = 0;
  /// Last value of each component: the update kinds of this sensor side by side (e.g. an
  /// attitude sensor: roll, pitch from "roll/pitch", then heading from "heading").
  std::array<InnovationComponent, kMaxInnovationComponents> last{};
  int num_components = 0;
  std::array<const char*, 3> kinds{};  ///< update kinds seen, in order
  std::array<int, 3> kind_offset{};    ///< their first component in `last`
};

/// νᵀ S⁻¹ ν by Cholesky; nullopt when S is not positive definite or the result is not finite.
std::optional<double> nis_of(const MeasVec& nu, const MeasCov& S);

/// The innovation of an update (see the file comment); P is the 12 x 12 robot covariance.
template <class Model>
InnovationSample innovation_sample(const Model& model, const MeasVec& z, const MeasVec& h,
                                   const MeasJac& H, const Mat12& P, const MeasCov& R);

/// Mean NIS and measurement dimension between two snapshots of one sensor (`before` null: since
/// the start); nis_mean = -1 when no valid update came in between.
struct InnovationPeriod {
  std::uint64_t updates = 0;
  double nis_mean = -1.0;
  double dim_mean = 0.0;
};
InnovationPeriod innovation_period(const SensorInnovation& now, const SensorInnovation* before);

class SensorInnovationStats {
 public:
  /// Records one update of `sensor` of kind `what` (a string literal: kinds are told apart by
  /// address) at t_us; `fused` = the gate passed it and the ESDF applied it, `reset` = the
  /// gate's timeout reset passed it; gate_sigma = its gate in sigmas (<= 0: off).
  void record(const SensorModels& models, std::size_t sensor, const char* what, std::int64_t t_us,
              const MeasVec& z, const MeasCov& R, const InnovationSample& sample, bool fused,
              bool reset = false, double gate_sigma = kTestRatioGateSigma);
  /// One entry per sensor that has had an update, in order of first update.
  const std::vector<SensorInnovation>& sensors() const { return sensors_; }

 private:
  SensorInnovation& slot(const SensorModels& models, std::size_t sensor);
  std::vector<SensorInnovation> sensors_;
  std::vector<int> index_of_sensor_;  ///< sensor -> sensors_ index (-1 none)
};

template <class Model>
InnovationSample innovation_sample(const Model& model, const MeasVec& z, const MeasVec& h,
                                   const MeasJac& H, const Mat12& P, const MeasCov& R) {
  InnovationSample s;
  s.nu = z - h;
  wrap_angle_rows(model, s.nu);
  s.S = H * P * H.transpose() + R;
  if (!s.nu.allFinite()) return s;
  if (const std::optional<double> nis = nis_of(s.nu, s.S)) {
    s.nis = *nis;
    s.valid = true;
  }
  return s;
}

}  // namespace nav::core
