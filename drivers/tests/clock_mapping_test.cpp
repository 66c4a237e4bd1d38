// Sensor clock -> host clock mapping on a simulated sensor: drift, offset, exponential and
// uniform receive-latency jitter, counter wraparound, reboots, latency spikes. The mapping
// error (mapped host time of validity minus the true one) must stay far below the jitter.

#include "nav/drivers/time/clock_mapping.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

namespace nav::drivers {
namespace {

/// Simulated sensor: its clock reads sensor(t) = s0 + (t - t0) * (1 + drift), counted in
/// `tick_us` steps and wrapped at `modulus_us` (0: never); messages reach the host after
/// `min_latency_us` + jitter.
struct SimSensor {
  double drift = 50e-6;
  int64_t s0_us = 123'456'789;
  int64_t t0_us = 1'000'000'000;  ///< host time (µs) when the sensor read s0
  int64_t tick_us = 1;
  int64_t modulus_us = 0;
  int64_t min_latency_us = 800;

  int64_t sensor_at(int64_t t_us) const {
    const double s = static_cast<double>(s0_us) + static_cast<double>(t_us - t0_us) * (1 + drift);
    int64_t v = static_cast<int64_t>(std::floor(s / static_cast<double>(tick_us))) * tick_us;
    if (modulus_us > 0) v = ((v % modulus_us) + modulus_us) % modulus_us;
    return v;
  }
};

struct ErrorStats {
  double max_abs_us = 0.0;
  double rms_us = 0.0;
  size_t checked = 0;
};

/// Runs `seconds` of 10 Hz samples through the mapping; after `warmup_s` checks the mapping
/// of every sample's sensor time against its true host time of validity.
ErrorStats run(ClockMapping& mapping, const SimSensor& sensor, double seconds, double warmup_s,
               const std::function<double()>& jitter_us, int64_t start_us = 1'000'000'000) {
  ErrorStats e;
  double sum_sq = 0.0;
  const int64_t period_us = 100'000;
  for (int64_t t = start_us; t < start_us + static_cast<int64_t>(seconds * 1e6); t += period_us) {
    const int64_t sensor_us = sensor.sensor_at(t);
    const auto host_us = t + sensor.min_latency_us + static_cast<int64_t>(jitter_us());
    mapping.update(sensor_us, host_us);
    if (static_cast<double>(t - start_us) < warmup_s * 1e6) continue;
    const auto mapped = mapping.to_host_us(sensor_us);
    if (!mapped) {
      ADD_FAILURE() << "not initialised at t=" << t;
      return e;
    }
    const double err = static_cast<double>(*mapped - t);
    e.max_abs_us = std::max(e.max_abs_us, std::abs(err));
    sum_sq += err * err;
    ++e.checked;
  }
  e.rms_us = e.checked > 0 ? std::sqrt(sum_sq / static_cast<double>(e.checked)) : 0.0;
  return e;
}

ClockMappingOptions options_for(const SimSensor& s) {
  ClockMappingOptions o;
  o.sensor_modulus_us = s.modulus_us;
  o.fixed_latency_us = s.min_latency_us;  // the known part of the transport delay
  return o;
}

TEST(ClockMapping, ExponentialJitterWithDriftAndOffset) {
  // 50 ppm drift, offset ~1e9 µs, latency 0.8 ms + Exp(mean 5 ms) (std 5 ms).
  SimSensor sensor;
  ClockMapping mapping(options_for(sensor));
  std::mt19937_64 rng(1);
  std::exponential_distribution<double> jitter(1.0 / 5000.0);
  const ErrorStats e = run(mapping, sensor, 300.0, 20.0, [&] { return jitter(rng); });
  std::printf("exponential jitter 5 ms mean: max |error| %.0f us, rms %.0f us over %zu samples\n",
              e.max_abs_us, e.rms_us, e.checked);
  EXPECT_GT(e.checked, 2700u);
  EXPECT_LT(e.max_abs_us, 500.0);  // < 1/10 of the 5 ms jitter
  EXPECT_LT(e.rms_us, 200.0);
  ASSERT_TRUE(mapping.fit());
  EXPECT_NEAR(mapping.fit()->drift, -sensor.drift / (1 + sensor.drift), 5e-6);
  EXPECT_EQ(mapping.stats().resets, 0u);
}

TEST(ClockMapping, UniformJitterAndNegativeDrift) {
  SimSensor sensor;
  sensor.drift = -80e-6;
  ClockMapping mapping(options_for(sensor));
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> jitter(0.0, 20'000.0);  // 0..20 ms, std 5.8 ms
  const ErrorStats e = run(mapping, sensor, 200.0, 20.0, [&] { return jitter(rng); });
  std::printf("uniform jitter 0..20 ms: max |error| %.0f us, rms %.0f us\n", e.max_abs_us,
              e.rms_us);
  EXPECT_LT(e.max_abs_us, 1000.0);  // < 1/20 of the 20 ms jitter span
  EXPECT_LT(e.rms_us, 400.0);
}

TEST(ClockMapping, SixteenBitMillisecondCounterWraps) {
  // A 16-bit ms counter wraps every 65.536 s: from 60 s to 460 s it wraps seven times.
  SimSensor sensor;
  sensor.tick_us = 1000;
  sensor.modulus_us = 65'536'000;
  sensor.s0_us = 60'000'000;  // first wrap after 5.5 s
  ClockMappingOptions options = options_for(sensor);
  options.sensor_resolution_us = 1000;  // the counter truncates to whole milliseconds
  ClockMapping mapping(options);
  std::mt19937_64 rng(3);
  std::exponential_distribution<double> jitter(1.0 / 3000.0);
  const ErrorStats e = run(mapping, sensor, 400.0, 20.0, [&] { return jitter(rng); });
  std::printf("16-bit ms counter, 3 ms jitter: max |error| %.0f us, rms %.0f us, wraps %llu\n",
              e.max_abs_us, e.rms_us, static_cast<unsigned long long>(mapping.stats().wraps));
  EXPECT_EQ(mapping.stats().wraps, 7u);
  EXPECT_EQ(mapping.stats().resets, 0u);
  // The 1 ms truncation dominates: ±0.5 ms, and its pattern (5 µs more per sample at 50 ppm,
  // a 20 s sawtooth) tilts the drift estimate while the window holds few of its periods.
  EXPECT_LT(e.max_abs_us, 1600.0);
  EXPECT_LT(e.rms_us, 400.0);
}

TEST(ClockMapping, LongGapIsUnwrappedWithTheHostClock) {
  // Sensor time 123 s .. 153 s, then silence for 150 s (more than two 65.5 s periods), then
  // samples again from 303 s: the host time elapsed picks the right period (3 wraps in all).
  SimSensor sensor;
  sensor.tick_us = 1000;
  sensor.modulus_us = 65'536'000;
  ClockMapping mapping(options_for(sensor));
  auto no_jitter = [] { return 0.0; };
  run(mapping, sensor, 30.0, 30.0, no_jitter);
  const ErrorStats e = run(mapping, sensor, 20.0, 0.0, no_jitter, 1'000'000'000 + 180'000'000);
  EXPECT_EQ(mapping.stats().resets, 0u);
  EXPECT_EQ(mapping.stats().wraps, 3u);
  EXPECT_LT(e.max_abs_us, 1500.0);
}

TEST(ClockMapping, SensorRebootIsDetectedAndRecovers) {
  SimSensor sensor;
  ClockMapping mapping(options_for(sensor));
  std::mt19937_64 rng(4);
  std::exponential_distribution<double> jitter(1.0 / 2000.0);
  auto j = [&] { return jitter(rng); };
  run(mapping, sensor, 100.0, 100.0, j);
  // Reboot: the counter restarts near zero (a jump back by ~223 s).
  SimSensor rebooted = sensor;
  rebooted.t0_us = 1'000'000'000 + 100'000'000;
  rebooted.s0_us = 0;
  const ErrorStats e = run(mapping, rebooted, 100.0, 30.0, j, rebooted.t0_us);
  EXPECT_EQ(mapping.stats().resets, 1u);
  EXPECT_EQ(mapping.stats().outliers, 2u);  // reset_confirm_samples - 1 before confirming
  EXPECT_LT(e.max_abs_us, 500.0);
  // Forward jump (e.g. sensor clock set to a new epoch): immediate reset.
  SimSensor jumped = rebooted;
  jumped.s0_us = 5'000'000'000;
  jumped.t0_us = rebooted.t0_us + 100'000'000;
  const ErrorStats e2 = run(mapping, jumped, 60.0, 30.0, j, jumped.t0_us);
  EXPECT_EQ(mapping.stats().resets, 2u);
  EXPECT_LT(e2.max_abs_us, 500.0);
}

TEST(ClockMapping, SingleLatencySpikeIsAnOutlierNotAReset) {
  SimSensor sensor;
  ClockMapping mapping(options_for(sensor));
  auto no_jitter = [] { return 100.0; };
  run(mapping, sensor, 30.0, 30.0, no_jitter);
  const int64_t t = 1'000'000'000 + 30'000'000;
  EXPECT_EQ(mapping.update(sensor.sensor_at(t), t + 2'000'000), ClockSampleResult::kOutlier);
  const ErrorStats e = run(mapping, sensor, 10.0, 0.0, no_jitter, t + 100'000);
  EXPECT_EQ(mapping.stats().resets, 0u);
  EXPECT_EQ(mapping.stats().outliers, 1u);
  EXPECT_LT(e.max_abs_us, 150.0);
}

TEST(ClockMapping, NeedsTwoSamplesAndRejectsInvalidInput) {
  ClockMappingOptions o;
  o.sensor_modulus_us = 1'000'000'000;
  ClockMapping mapping(o);
  EXPECT_FALSE(mapping.to_host_us(0).has_value());
  EXPECT_EQ(mapping.update(1'000, 50'000), ClockSampleResult::kAccepted);
  EXPECT_FALSE(mapping.to_host_us(1'000).has_value());
  EXPECT_EQ(mapping.update(-1, 60'000), ClockSampleResult::kInvalid);
  EXPECT_EQ(mapping.update(1'000'000'000, 60'000), ClockSampleResult::kInvalid);
  EXPECT_EQ(mapping.update(11'000, 40'000), ClockSampleResult::kInvalid);  // host backwards
  EXPECT_EQ(mapping.update(11'000, 60'000), ClockSampleResult::kAccepted);
  ASSERT_TRUE(mapping.to_host_us(6'000).has_value());
  EXPECT_EQ(*mapping.to_host_us(6'000), 55'000);
  EXPECT_EQ(mapping.stats().invalid, 3u);
}

TEST(ClockMapping, UncertaintyIsSmallInsideAndGrowsOutsideTheWindow) {
  SimSensor sensor;
  ClockMapping mapping(options_for(sensor));
  std::mt19937_64 rng(5);
  std::exponential_distribution<double> jitter(1.0 / 5000.0);
  run(mapping, sensor, 120.0, 120.0, [&] { return jitter(rng); });
  const int64_t centre = mapping.fit()->center_sensor_us;
  const double inside = *mapping.uncertainty_us(centre);
  const double outside = *mapping.uncertainty_us(centre + 300'000'000);
  EXPECT_GT(inside, 0.0);
  EXPECT_LT(inside, 100.0);  // ~ 5 ms mean latency / 600 samples
  EXPECT_GT(outside, 5.0 * inside);
}

TEST(ClockMapping, ArbitrarySamplesKeepCountersAndOutputsSane) {
  ClockMappingOptions o;
  o.sensor_modulus_us = 65'536'000;
  o.max_samples = 50;
  ClockMapping mapping(o);
  std::mt19937_64 rng(6);
  int64_t host = 0;
  for (int i = 0; i < 20000; ++i) {
    host += static_cast<int64_t>(rng() % 3'000'000) - 100'000;  // sometimes backwards
    const int64_t sensor = static_cast<int64_t>(rng() % 70'000'000) - 1'000'000;
    mapping.update(sensor, host);
    if (const auto mapped = mapping.to_host_us(sensor)) {
      EXPECT_LT(std::abs(*mapped - host), int64_t{1} << 40);
      EXPECT_TRUE(std::isfinite(*mapping.uncertainty_us(sensor)));
    }
  }
  const ClockMappingStats& s = mapping.stats();
  EXPECT_EQ(s.samples, 20000u);
  EXPECT_EQ(s.accepted + s.outliers + s.resets + s.invalid, s.samples);
  EXPECT_GT(s.invalid, 0u);
  EXPECT_GT(s.resets, 0u);
}

TEST(ClockMapping, OptionsValidateNamesTheField) {
  ClockMappingOptions o;
  EXPECT_EQ(o.validate(), "");
  o.max_samples = 1;
  EXPECT_EQ(o.validate().rfind("max_samples", 0), 0u);
  o = {};
  o.sensor_modulus_us = 1'000'000;
  EXPECT_EQ(o.validate().rfind("jump_threshold_us", 0), 0u);
  EXPECT_THROW(ClockMapping{o}, std::invalid_argument);
}

}  // namespace
}  // namespace nav::drivers
