// Sensor clock -> host clock mapping by the lower envelope of (sensor, host - sensor); see
// clock_mapping.h for the model and the references.
#include "nav/drivers/time/clock_mapping.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace nav::drivers {
namespace {

/// floor(a / b) for b > 0.
int64_t floor_div(int64_t a, int64_t b) {
  const int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

}  // namespace

std::string ClockMappingOptions::validate() const {
  std::ostringstream e;
  if (sensor_modulus_us < 0) {
    e << "sensor_modulus_us: " << sensor_modulus_us << " must be >= 0 (0 = no wraparound)";
  } else if (window_us <= 0) {
    e << "window_us: " << window_us << " must be > 0";
  } else if (max_samples < 2) {
    e << "max_samples: " << max_samples << " must be >= 2";
  } else if (!(max_drift_ppm >= 0.0 && max_drift_ppm <= 1e5)) {
    e << "max_drift_ppm: " << max_drift_ppm << " is not in 0..100000";
  } else if (jump_threshold_us <= 0) {
    e << "jump_threshold_us: " << jump_threshold_us << " must be > 0";
  } else if (sensor_modulus_us > 0 && jump_threshold_us >= sensor_modulus_us / 2) {
    e << "jump_threshold_us: " << jump_threshold_us << " must be below half the sensor modulus ("
      << sensor_modulus_us / 2 << ")";
  } else if (sensor_resolution_us < 0) {
    e << "sensor_resolution_us: " << sensor_resolution_us << " must be >= 0";
  } else if (reset_confirm_samples < 1) {
    e << "reset_confirm_samples: must be >= 1";
  }
  return e.str();
}

ClockMapping::ClockMapping(ClockMappingOptions options) : options_(options) {
  if (std::string err = options_.validate(); !err.empty()) {
    throw std::invalid_argument("ClockMappingOptions." + err);
  }
  window_.reserve(options_.max_samples + 1);
  hull_x_.reserve(options_.max_samples + 1);
  hull_y_.reserve(options_.max_samples + 1);
}

void ClockMapping::clear() {
  window_.clear();
  pending_.clear();
  last_.reset();
  fit_.reset();
}

int64_t ClockMapping::unwrap(int64_t sensor_us, int64_t expected_us) const {
  const int64_t m = options_.sensor_modulus_us;
  if (m == 0) return sensor_us;
  // The period k that puts sensor_us + k*m closest to the expected unwrapped time.
  const int64_t k = floor_div(expected_us - sensor_us + m / 2, m);
  return sensor_us + k * m;
}

double ClockMapping::envelope_at(int64_t sensor_unwrapped_us) const {
  if (fit_) {
    return fit_->offset_us +
           fit_->drift * static_cast<double>(sensor_unwrapped_us - fit_->ref_sensor_us);
  }
  // One sample so far: its own offset, no drift.
  return static_cast<double>(window_.front().host_us - window_.front().sensor_us);
}

void ClockMapping::restart_from(const Sample& s) {
  window_.clear();
  pending_.clear();
  window_.push_back(s);
  refit();
}

ClockSampleResult ClockMapping::update(int64_t sensor_us, int64_t host_us) {
  ++stats_.samples;
  const int64_t m = options_.sensor_modulus_us;
  const bool out_of_period = m > 0 && (sensor_us < 0 || sensor_us >= m);
  // Times within ±2^53 µs (285 years) keep every double below exact.
  constexpr int64_t kLimit = int64_t{1} << 53;
  if (out_of_period || std::abs(sensor_us) >= kLimit || std::abs(host_us) >= kLimit ||
      (last_ && host_us < last_->host_us)) {
    ++stats_.invalid;
    return ClockSampleResult::kInvalid;
  }
  Sample s{sensor_us, host_us};
  if (last_) {
    s.sensor_us = unwrap(sensor_us, last_->sensor_us + (host_us - last_->host_us));
    if (m > 0) {
      const int64_t periods = floor_div(s.sensor_us, m) - floor_div(last_->sensor_us, m);
      if (periods > 0) stats_.wraps += static_cast<uint64_t>(periods);
    }
  }
  last_ = s;
  if (window_.empty()) {
    restart_from(s);
    ++stats_.accepted;
    return ClockSampleResult::kAccepted;
  }
  const double y = static_cast<double>(s.host_us - s.sensor_us);
  const double residual = y - envelope_at(s.sensor_us);
  const auto threshold = static_cast<double>(options_.jump_threshold_us);
  if (residual < -threshold) {
    // Earlier than the fastest delivery so far allows: the sensor clock jumped forward.
    ++stats_.resets;
    restart_from(s);
    return ClockSampleResult::kReset;
  }
  if (residual > threshold) {
    // A latency spike or a backwards jump; a jump shows in consecutive samples that agree.
    if (!pending_.empty()) {
      const double y0 = static_cast<double>(pending_.front().host_us - pending_.front().sensor_us);
      if (std::abs(y - y0) > threshold) pending_.clear();
    }
    pending_.push_back(s);
    if (pending_.size() >= options_.reset_confirm_samples) {
      ++stats_.resets;
      window_ = pending_;
      pending_.clear();
      refit();
      return ClockSampleResult::kReset;
    }
    ++stats_.outliers;
    return ClockSampleResult::kOutlier;
  }
  pending_.clear();
  // Keep the window ordered by sensor time (a late sample is inserted in place).
  auto pos =
      std::upper_bound(window_.begin(), window_.end(), s,
                       [](const Sample& a, const Sample& b) { return a.sensor_us < b.sensor_us; });
  window_.insert(pos, s);
  const int64_t newest = window_.back().sensor_us;
  auto first_kept = window_.begin();
  // Old samples leave the window, but two always stay so that a gap in the data (longer
  // than the window) does not leave the mapping without a fit.
  while (window_.end() - first_kept > 2 &&
         (first_kept->sensor_us < newest - options_.window_us ||
          static_cast<size_t>(window_.end() - first_kept) > options_.max_samples)) {
    ++first_kept;
  }
  window_.erase(window_.begin(), first_kept);
  refit();
  ++stats_.accepted;
  return ClockSampleResult::kAccepted;
}

void ClockMapping::refit() {
  const size_t n = window_.size();
  const int64_t ref = window_.back().sensor_us;
  const int64_t span = window_.back().sensor_us - window_.front().sensor_us;
  if (n < 2 || span <= 0) {
    fit_.reset();
    return;
  }
  const double y_ref = static_cast<double>(window_.back().host_us - window_.back().sensor_us);
  auto x_of = [&](const Sample& s) { return static_cast<double>(s.sensor_us - ref); };
  auto y_of = [&](const Sample& s) { return static_cast<double>(s.host_us - s.sensor_us) - y_ref; };
  // Lower convex hull (Andrew's monotone chain) of the points sorted by x.
  hull_x_.clear();
  hull_y_.clear();
  double x_mean = 0.0;
  for (const Sample& s : window_) {
    const double x = x_of(s);
    const double y = y_of(s);
    x_mean += x;
    if (!hull_x_.empty() && hull_x_.back() == x) {
      if (y >= hull_y_.back()) continue;  // same sensor time: keep the lower point
      hull_x_.pop_back();
      hull_y_.pop_back();
    }
    while (hull_x_.size() >= 2) {
      const size_t k = hull_x_.size();
      const double cross = (hull_x_[k - 1] - hull_x_[k - 2]) * (y - hull_y_[k - 2]) -
                           (hull_y_[k - 1] - hull_y_[k - 2]) * (x - hull_x_[k - 2]);
      if (cross > 0.0) break;  // left turn: convex from below
      hull_x_.pop_back();
      hull_y_.pop_back();
    }
    hull_x_.push_back(x);
    hull_y_.push_back(y);
  }
  x_mean /= static_cast<double>(n);
  // The hull edge over the mean maximises the line's height there (slopes increase along
  // the hull); with the drift bound the optimum is the clamped slope (the height is concave).
  double slope = 0.0;
  for (size_t k = 0; k + 1 < hull_x_.size(); ++k) {
    slope = (hull_y_[k + 1] - hull_y_[k]) / (hull_x_[k + 1] - hull_x_[k]);
    if (hull_x_[k + 1] >= x_mean) break;
  }
  const double bound = options_.max_drift_ppm * 1e-6;
  slope = std::clamp(slope, -bound, bound);
  double height = std::numeric_limits<double>::infinity();  // line height at x_mean
  for (const Sample& s : window_) height = std::min(height, y_of(s) - slope * (x_of(s) - x_mean));
  double residual_sum = 0.0;
  for (const Sample& s : window_) residual_sum += y_of(s) - (height + slope * (x_of(s) - x_mean));
  ClockFit fit;
  fit.ref_sensor_us = ref;
  fit.center_sensor_us = ref + static_cast<int64_t>(std::llround(x_mean));
  fit.offset_us = y_ref + height - slope * x_mean;
  fit.drift = slope;
  fit.samples = n;
  fit.span_us = span;
  fit.mean_residual_us = residual_sum / static_cast<double>(n);
  fit_ = fit;
}

std::optional<int64_t> ClockMapping::to_host_us(int64_t sensor_us) const {
  if (!fit_) return std::nullopt;
  constexpr int64_t kLimit = int64_t{1} << 53;
  if (std::abs(sensor_us) >= kLimit) return std::nullopt;
  const int64_t s = unwrap(sensor_us, window_.back().sensor_us);
  const double host = static_cast<double>(s) + envelope_at(s) -
                      static_cast<double>(options_.fixed_latency_us) +
                      0.5 * static_cast<double>(options_.sensor_resolution_us);
  if (!(std::abs(host) < static_cast<double>(kLimit))) return std::nullopt;
  return std::llround(host);
}

std::optional<double> ClockMapping::uncertainty_us(int64_t sensor_us) const {
  if (!fit_) return std::nullopt;
  const int64_t s = unwrap(sensor_us, window_.back().sensor_us);
  // The minimum of n latencies sits about mean/n above the true floor (exponential jitter);
  // the slope error of an edge spanning the window is about twice that over the span.
  const double base = std::max(fit_->mean_residual_us / static_cast<double>(fit_->samples), 1.0);
  const double distance = std::abs(static_cast<double>(s - fit_->center_sensor_us));
  return base * (1.0 + 2.0 * distance / static_cast<double>(fit_->span_us));
}

}  // namespace nav::drivers
