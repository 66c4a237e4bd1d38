#pragma once
// Internal to nav_daemon: the common part of the sensor decoders (sensor_decoder.h) and the
// per-family factories (sensor_decoder_dvl.cpp, sensor_decoder_ascii.cpp).

#include <cstdint>
#include <memory>

#include "nav/daemon/sources/sensor_decoder.h"
#include "nav/drivers/codecs/decode_stats.h"
#include "nav/drivers/time/timestamps.h"

namespace nav::daemon::detail {

/// Time stamping and counters shared by every decoder.
class DecoderBase : public SensorDecoder {
 public:
  DecoderBase(const SensorConfig& sensor, std::uint16_t sensor_index);

 protected:
  /// Measurement time valid at `validity_us`, received at `host`.
  MeasurementTime stamp(std::int64_t validity_us, const drivers::HostTime& host) const;
  /// host_monotonic - latency: the validity of a record without a usable device time.
  std::int64_t host_validity_us(const drivers::HostTime& host) const {
    return host.monotonic_us - latency_us_;
  }
  /// Counters from a codec's stats plus this decoder's own (invalid, unused, ...).
  SensorDecoderCounters merge(const drivers::DecodeStats& codec) const;
  std::int64_t latency_us() const { return latency_us_; }

  SensorDecoderCounters own_;  ///< measurements, invalid, unused, unsupported_frame, device_clock

 private:
  std::uint16_t sensor_index_;
  std::int64_t latency_us_;
};

std::unique_ptr<SensorDecoder> make_pd0_decoder(const SensorConfig& sensor, std::uint16_t index,
                                                const SensorDecoderOptions& options);
std::unique_ptr<SensorDecoder> make_pd6_decoder(const SensorConfig& sensor, std::uint16_t index);
std::unique_ptr<SensorDecoder> make_can_dvl_decoder(const SensorConfig& sensor,
                                                    std::uint16_t index);
std::unique_ptr<SensorDecoder> make_nmea_decoder(const SensorConfig& sensor, std::uint16_t index);
std::unique_ptr<SensorDecoder> make_kvh_decoder(const SensorConfig& sensor, std::uint16_t index);
std::unique_ptr<SensorDecoder> make_paro_decoder(const SensorConfig& sensor, std::uint16_t index);
std::unique_ptr<SensorDecoder> make_altimeter_decoder(const SensorConfig& sensor,
                                                      std::uint16_t index);

}  // namespace nav::daemon::detail
