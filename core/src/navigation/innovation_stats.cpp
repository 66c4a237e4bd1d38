// Per-sensor innovation records of NavFilter's robot updates (navigation/innovation_stats.h).
#include "nav/core/navigation/innovation_stats.h"

#include <Eigen/Cholesky>

namespace nav::core {

std::optional<double> nis_of(const MeasVec& nu, const MeasCov& S) {
  const Eigen::LLT<MeasCov> llt(S);
  if (llt.info() != Eigen::Success) return std::nullopt;
  const double d2 = nu.dot(llt.solve(nu));
  if (!std::isfinite(d2)) return std::nullopt;
  return d2;
}

InnovationPeriod innovation_period(const SensorInnovation& now, const SensorInnovation* before) {
  InnovationPeriod p;
  const std::uint64_t n0 = before ? before->nis_count : 0;
  p.updates = now.updates - (before ? before->updates : 0);
  const std::uint64_t n = now.nis_count - n0;
  if (n == 0) return p;
  p.nis_mean = (now.nis_sum - (before ? before->nis_sum : 0.0)) / static_cast<double>(n);
  p.dim_mean = (now.dim_sum - (before ? before->dim_sum : 0.0)) / static_cast<double>(n);
  return p;
}

SensorInnovation& SensorInnovationStats::slot(const SensorModels& models, std::size_t sensor) {
  if (sensor >= index_of_sensor_.size()) index_of_sensor_.resize(sensor + 1, -1);
  int& index = index_of_sensor_[sensor];
  if (index < 0) {
    index = static_cast<int>(sensors_.size());
    SensorInnovation& s = sensors_.emplace_back();
    s.sensor = sensor;
    s.name = models.name(sensor);
  }
  return sensors_[static_cast<std::size_t>(index)];
}

void SensorInnovationStats::record(const SensorModels& models, std::size_t sensor, const char* what,
                                   std::int64_t t_us, const MeasVec& z, const MeasCov& R,
                                   const InnovationSample& sample, bool fused, bool reset,
                                   double gate_sigma) {
  SensorInnovation& s = slot(models, sensor);
  const double g = gate_sigma > 0.0 ? gate_sigma : kTestRatioGateSigma;
  if (fused) {
    ++s.updates;
    if (reset) ++s.gate_resets;
  } else {
    ++s.rejected;
  }
  const int dim = static_cast<int>(z.size());
  if (sample.valid) {  // gated ones too: the monitor shows what the sensor said
    ++s.nis_count;
    s.nis_sum += sample.nis;
    s.dim_sum += dim;
    s.nis_last = sample.nis;
    s.dim_last = dim;
  }
  // This kind's components in `last` (a new kind appends its rows while there is room).
  std::size_t k = 0;
  while (k < s.kinds.size() && s.kinds[k] != nullptr && s.kinds[k] != what) ++k;
  if (k == s.kinds.size()) return;
  if (s.kinds[k] == nullptr) {
    if (s.num_components + dim > kMaxInnovationComponents) return;
    s.kinds[k] = what;
    s.kind_offset[k] = s.num_components;
    s.num_components += dim;
  }
  for (int row = 0; row < dim; ++row) {
    InnovationComponent& c = s.last[static_cast<std::size_t>(s.kind_offset[k] + row)];
    c.time_of_validity_us = t_us;
    c.observation = z(row);
    c.observation_variance = R(row, row);
    c.innovation = sample.nu.size() > row ? sample.nu(row) : 0.0;
    c.innovation_variance = sample.S.rows() > row ? sample.S(row, row) : 0.0;
    c.test_ratio = c.innovation_variance > 0.0
                       ? c.innovation * c.innovation / (g * g * c.innovation_variance)
                       : 0.0;
    c.fused = fused;
  }
}

}  // namespace nav::core
