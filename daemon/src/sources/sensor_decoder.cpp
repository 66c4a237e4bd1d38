// Sensor decoders (nav/daemon/sources/sensor_decoder.h): the shared base and the factory.
#include "nav/daemon/sources/sensor_decoder.h"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include "nav/drivers/codecs/candump_log.h"
#include "sensor_decoder_impl.h"

namespace nav::daemon {

void SensorDecoder::feed_frame(const drivers::CanFrame& /*frame*/,
                               std::vector<Measurement>& /*out*/) {
  ++misrouted_frames_;  // reported in decode_errors by the decoders
}

bool has_sensor_decoder(SensorType type) { return !is_camera(type); }

std::unique_ptr<SensorDecoder> make_sensor_decoder(const SensorConfig& sensor,
                                                   std::uint16_t sensor_index,
                                                   const SensorDecoderOptions& options) {
  switch (sensor.type) {
    case SensorType::kDvlPd0:
      return detail::make_pd0_decoder(sensor, sensor_index, options);
    case SensorType::kDvlPd6:
      return detail::make_pd6_decoder(sensor, sensor_index);
    case SensorType::kDvlCan:
      return detail::make_can_dvl_decoder(sensor, sensor_index);
    case SensorType::kHeadingNmea:
      return detail::make_nmea_decoder(sensor, sensor_index);
    case SensorType::kFogKvh:
      return detail::make_kvh_decoder(sensor, sensor_index);
    case SensorType::kPressureParo:
      return detail::make_paro_decoder(sensor, sensor_index);
    case SensorType::kAltimeter:
      return detail::make_altimeter_decoder(sensor, sensor_index);
    case SensorType::kCameraGige:
    case SensorType::kCameraV4l2:
      break;
  }
  throw std::invalid_argument("sensor '" + sensor.name + "': a " + to_string(sensor.type) +
                              " sensor has no byte decoder (camera frames are ImageEvents)");
}

std::string can_frame_log_line(const drivers::CanFrame& frame, const std::string& interface) {
  drivers::CanLogFrame f;
  f.id = frame.id;
  f.extended = frame.extended;
  f.remote = frame.remote;
  f.dlc = frame.dlc;
  f.data = frame.data;
  const std::int64_t t_us = frame.kernel_realtime_us.value_or(frame.received.realtime_us);
  f.time.realtime_us = t_us;
  f.time.monotonic_us = t_us;
  std::strncpy(f.interface_name.data(), interface.c_str(), f.interface_name.size() - 1);
  std::string line = drivers::format_candump_log_line(f);
  if (line.empty() || line.back() != '\n') line += '\n';
  return line;
}

namespace detail {

DecoderBase::DecoderBase(const SensorConfig& sensor, std::uint16_t sensor_index)
    : SensorDecoder(sensor.name),
      sensor_index_(sensor_index),
      latency_us_(std::llround(sensor.latency_s * 1e6)) {}

MeasurementTime DecoderBase::stamp(std::int64_t validity_us, const drivers::HostTime& host) const {
  MeasurementTime t;
  t.validity_us = validity_us;
  t.host_monotonic_us = host.monotonic_us;
  t.host_realtime_us = host.realtime_us;
  t.sensor_index = sensor_index_;
  return t;
}

SensorDecoderCounters DecoderBase::merge(const drivers::DecodeStats& codec) const {
  SensorDecoderCounters c = own_;
  c.bytes = codec.bytes;
  c.messages = codec.records;
  c.decode_errors =
      codec.checksum_failures + codec.malformed + codec.out_of_range + misrouted_frames_;
  c.out_of_range = codec.out_of_range;
  c.dropped_bytes = codec.dropped_bytes;
  c.unused += codec.unsupported;
  return c;
}

}  // namespace detail
}  // namespace nav::daemon
