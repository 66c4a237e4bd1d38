// ASCII-line sensor decoders (sensor_decoder.h): NMEA heading/attitude (iXblue Octans), KVH
// DSP-3000 rate gyro, Paroscientific pressure -> depth (UNESCO 1983), PA500 altimeter. None of
// these protocols carries a device time: validity = host_monotonic - latency.
#include <numbers>
#include <type_traits>

#include "nav/drivers/codecs/altimeter.h"
#include "nav/drivers/codecs/kvh.h"
#include "nav/drivers/codecs/nmea.h"
#include "nav/drivers/codecs/paroscientific.h"
#include "nav/drivers/codecs/seawater.h"
#include "sensor_decoder_impl.h"

namespace nav::daemon::detail {
namespace {

/// A decoder around one streaming codec: feeds it and turns each record into at most one
/// measurement with `Derived::convert(record, out)`.
template <typename Codec, typename Record, typename Derived>
class LineDecoder : public DecoderBase {
 public:
  using DecoderBase::DecoderBase;

  void feed(std::span<const std::uint8_t> bytes, std::int64_t host_realtime_us,
            std::int64_t host_monotonic_us, std::vector<Measurement>& out) override {
    records_.clear();
    codec_.feed(bytes, drivers::HostTime{host_monotonic_us, host_realtime_us}, records_);
    for (const Record& r : records_) static_cast<Derived*>(this)->convert(r, out);
  }
  SensorDecoderCounters counters() const override { return merge(codec_.stats()); }

 protected:
  template <typename M>
  void push(M m, const drivers::HostTime& host, std::vector<Measurement>& out) {
    m.time = stamp(host_validity_us(host), host);
    out.emplace_back(m);
    ++own_.measurements;
  }

  Codec codec_;
  std::vector<Record> records_;
};

class NmeaSensorDecoder final
    : public LineDecoder<drivers::NmeaDecoder, drivers::NmeaRecord, NmeaSensorDecoder> {
 public:
  using LineDecoder::LineDecoder;
  void convert(const drivers::NmeaRecord& r, std::vector<Measurement>& out) {
    if (const auto* h = std::get_if<drivers::NmeaHeading>(&r)) {
      Attitude a;
      a.heading_rad = h->heading_rad;
      a.has_roll_pitch = false;
      push(a, h->time.host, out);
    } else if (const auto* rp = std::get_if<drivers::NmeaAttitude>(&r)) {
      Attitude a;
      a.roll_rad = rp->roll_rad;
      a.pitch_rad = rp->pitch_rad;
      a.has_heading = false;
      push(a, rp->time.host, out);
    } else {
      ++own_.unused;  // position, speed, standard deviations, status words
    }
  }
};

/// KVH DSP-3000 in rate mode (the codec's default): a single-axis rate about the sensor z axis.
class KvhSensorDecoder final
    : public LineDecoder<drivers::KvhDecoder, drivers::KvhRecord, KvhSensorDecoder> {
 public:
  using LineDecoder::LineDecoder;
  void convert(const drivers::KvhRecord& r, std::vector<Measurement>& out) {
    if (!r.sensor_valid || !r.rate_radps) {
      ++own_.invalid;
      return;
    }
    AngularRate w;
    w.omega_sensor_radps = {0.0, 0.0, *r.rate_radps};
    w.has_axis = {false, false, true};
    push(w, r.time.host, out);
  }
};

class ParoSensorDecoder final
    : public LineDecoder<drivers::ParoDecoder, drivers::ParoRecord, ParoSensorDecoder> {
 public:
  explicit ParoSensorDecoder(const SensorConfig& sensor, std::uint16_t index)
      : LineDecoder(sensor, index) {
    depth_options_.latitude_rad = sensor.pressure.latitude_deg * std::numbers::pi / 180.0;
    depth_options_.atmospheric_pressure_pa =
        sensor.pressure.surface_pressure_dbar * drivers::kPascalPerDecibar;
  }
  void convert(const drivers::ParoRecord& r, std::vector<Measurement>& out) {
    const std::optional<double> depth_m =
        drivers::depth_from_pressure_m(r.pressure_pa, depth_options_);
    if (!depth_m) {
      ++own_.invalid;  // in air, wrong tare, beyond the deepest ocean
      return;
    }
    Depth d;
    d.depth_m = *depth_m;
    push(d, r.time.host, out);
  }

 private:
  drivers::DepthConversionOptions depth_options_;
};

class AltimeterSensorDecoder final
    : public LineDecoder<drivers::AltimeterDecoder, drivers::AltimeterRecord,
                         AltimeterSensorDecoder> {
 public:
  using LineDecoder::LineDecoder;
  void convert(const drivers::AltimeterRecord& r, std::vector<Measurement>& out) {
    if (r.status != drivers::AltimeterStatus::kValid || !r.range_m) {
      ++own_.invalid;  // no bottom echo or out of the instrument's range
      return;
    }
    Altitude a;
    a.altitude_m = *r.range_m;
    push(a, r.time.host, out);
  }
};

}  // namespace

std::unique_ptr<SensorDecoder> make_nmea_decoder(const SensorConfig& sensor, std::uint16_t index) {
  return std::make_unique<NmeaSensorDecoder>(sensor, index);
}
std::unique_ptr<SensorDecoder> make_kvh_decoder(const SensorConfig& sensor, std::uint16_t index) {
  return std::make_unique<KvhSensorDecoder>(sensor, index);
}
std::unique_ptr<SensorDecoder> make_paro_decoder(const SensorConfig& sensor, std::uint16_t index) {
  return std::make_unique<ParoSensorDecoder>(sensor, index);
}
std::unique_ptr<SensorDecoder> make_altimeter_decoder(const SensorConfig& sensor,
                                                      std::uint16_t index) {
  return std::make_unique<AltimeterSensorDecoder>(sensor, index);
}

}  // namespace nav::daemon::detail
