// DVL sensor decoders (sensor_decoder.h): RDI PD0 with its RTC mapped onto the host clock, RDI
// PD6 (:BI lines) and a DVL on CAN (signal table with v_x_mps, v_y_mps, v_z_mps).
#include <optional>

#include "nav/drivers/codecs/candump_log.h"
#include "nav/drivers/codecs/pd0.h"
#include "nav/drivers/codecs/pd6.h"
#include "nav/drivers/config/can_frame_decoder.h"
#include "nav/drivers/time/clock_mapping.h"
#include "sensor_decoder_impl.h"

namespace nav::daemon::detail {
namespace {

/// Resolution of the PD0 RTC (hundredths of a second, truncated by the instrument).
constexpr std::int64_t kPd0RtcResolutionUs = 10'000;

class Pd0SensorDecoder final : public DecoderBase {
 public:
  Pd0SensorDecoder(const SensorConfig& sensor, std::uint16_t index,
                   const SensorDecoderOptions& options)
      : DecoderBase(sensor, index),
        min_clock_samples_(std::max<std::size_t>(options.min_clock_samples, 2)),
        clock_(clock_options(latency_us())) {}

  void feed(std::span<const std::uint8_t> bytes, std::int64_t host_realtime_us,
            std::int64_t host_monotonic_us, std::vector<Measurement>& out) override {
    ensembles_.clear();
    decoder_.feed(bytes, drivers::HostTime{host_monotonic_us, host_realtime_us}, ensembles_);
    for (const drivers::Pd0Ensemble& e : ensembles_) emit(e, out);
  }
  SensorDecoderCounters counters() const override { return merge(decoder_.stats()); }

 private:
  static drivers::ClockMappingOptions clock_options(std::int64_t latency_us) {
    drivers::ClockMappingOptions o;
    o.fixed_latency_us = latency_us;
    o.sensor_resolution_us = kPd0RtcResolutionUs;
    return o;
  }

  /// Validity from the RTC when the mapping is trusted for this sample, else host - latency.
  /// Every ensemble with an RTC time feeds the mapping, with or without a velocity.
  std::int64_t validity_us(const drivers::Pd0Ensemble& e, bool& from_device_clock) {
    from_device_clock = false;
    if (!e.time.sensor_time_us) return host_validity_us(e.time.host);
    const auto result = clock_.update(*e.time.sensor_time_us, e.time.host.monotonic_us);
    const bool trusted = result == drivers::ClockSampleResult::kAccepted && clock_.fit() &&
                         clock_.fit()->samples >= min_clock_samples_;
    const std::optional<std::int64_t> mapped =
        trusted ? clock_.to_host_us(*e.time.sensor_time_us) : std::nullopt;
    if (!mapped) return host_validity_us(e.time.host);
    from_device_clock = true;
    return *mapped;
  }

  void emit(const drivers::Pd0Ensemble& e, std::vector<Measurement>& out) {
    bool from_device_clock = false;
    const std::int64_t validity = validity_us(e, from_device_clock);
    if (e.coord_frame() != drivers::Pd0CoordFrame::kInstrument) {
      ++own_.unsupported_frame;
      return;
    }
    const auto& bt = e.bottom_track;
    if (!bt || !bt->velocity_mps[0] || !bt->velocity_mps[1] || !bt->velocity_mps[2]) {
      ++own_.invalid;
      return;
    }
    DvlVelocity m;
    m.time = stamp(validity, e.time.host);
    // PD0 bottom track is the bottom relative to the instrument: negate for the DVL's velocity.
    for (std::size_t i = 0; i < 3; ++i) m.v_sensor_mps[i] = -*bt->velocity_mps[i];
    out.emplace_back(m);
    ++own_.measurements;
    if (from_device_clock) ++own_.device_clock;
  }

  std::size_t min_clock_samples_;
  drivers::Pd0Decoder decoder_;
  drivers::ClockMapping clock_;
  std::vector<drivers::Pd0Ensemble> ensembles_;
};

class Pd6SensorDecoder final : public DecoderBase {
 public:
  using DecoderBase::DecoderBase;

  void feed(std::span<const std::uint8_t> bytes, std::int64_t host_realtime_us,
            std::int64_t host_monotonic_us, std::vector<Measurement>& out) override {
    records_.clear();
    decoder_.feed(bytes, drivers::HostTime{host_monotonic_us, host_realtime_us}, records_);
    for (const drivers::Pd6Record& r : records_) emit(r, out);
  }
  SensorDecoderCounters counters() const override { return merge(decoder_.stats()); }

 private:
  void emit(const drivers::Pd6Record& r, std::vector<Measurement>& out) {
    const auto* v = std::get_if<drivers::Pd6Velocity>(&r.value);
    if (v == nullptr || v->reference != drivers::Pd6Reference::kBottom) {
      ++own_.unused;  // attitude, timing, distance, water-mass lines
      return;
    }
    if (v->frame != drivers::Pd6Frame::kInstrument) {
      ++own_.unsupported_frame;
      return;
    }
    if (!v->valid || !v->velocity_mps[0] || !v->velocity_mps[1] || !v->velocity_mps[2]) {
      ++own_.invalid;
      return;
    }
    DvlVelocity m;
    m.time = stamp(host_validity_us(r.time.host), r.time.host);
    for (std::size_t i = 0; i < 3; ++i) m.v_sensor_mps[i] = *v->velocity_mps[i];
    out.emplace_back(m);
    ++own_.measurements;
  }

  drivers::Pd6Decoder decoder_;
  std::vector<drivers::Pd6Record> records_;
};

/// DVL on CAN: a message carrying v_x_mps, v_y_mps and v_z_mps (optionally bottom_track_valid)
/// in the signal table of the sensor's transport (config/can/dvl_fog_example.yaml).
class CanDvlSensorDecoder final : public DecoderBase {
 public:
  CanDvlSensorDecoder(const SensorConfig& sensor, std::uint16_t index)
      : DecoderBase(sensor, index), frames_(table(sensor), clock_options(latency_us())) {}

  void feed(std::span<const std::uint8_t> bytes, std::int64_t host_realtime_us,
            std::int64_t host_monotonic_us, std::vector<Measurement>& out) override {
    text_bytes_ += bytes.size();
    log_frames_.clear();
    const drivers::HostTime host{host_monotonic_us, host_realtime_us};
    candump_.feed(bytes, host, log_frames_);
    for (const drivers::CanLogFrame& f : log_frames_) {
      drivers::CanFrame frame;
      frame.id = f.id;
      frame.extended = f.extended;
      frame.remote = f.remote;
      frame.dlc = f.dlc;
      frame.data = f.data;
      frame.received = host;
      frame.kernel_realtime_us = f.time.realtime_us;
      decode(frame, out);
    }
  }
  void feed_frame(const drivers::CanFrame& frame, std::vector<Measurement>& out) override {
    frame_bytes_ += frame.remote ? 0 : frame.dlc;
    decode(frame, out);
  }
  SensorDecoderCounters counters() const override {
    SensorDecoderCounters c = merge(frames_.stats());
    const drivers::DecodeStats& text = candump_.stats();
    c.bytes = text_bytes_ + frame_bytes_;
    c.decode_errors += text.checksum_failures + text.malformed + text.out_of_range;
    c.out_of_range += text.out_of_range;
    c.dropped_bytes += text.dropped_bytes;
    c.unused += text.unsupported;
    return c;
  }

 private:
  static std::vector<drivers::CanMessageSpec> table(const SensorConfig& sensor) {
    const auto* can = std::get_if<CanTransport>(&sensor.transport);
    return can != nullptr ? can->signals.messages : std::vector<drivers::CanMessageSpec>{};
  }
  static drivers::ClockMappingOptions clock_options(std::int64_t latency_us) {
    drivers::ClockMappingOptions o;
    o.fixed_latency_us = latency_us;
    return o;
  }

  void decode(const drivers::CanFrame& frame, std::vector<Measurement>& out) {
    if (!frames_.decode(frame, message_)) return;  // counted by the frame decoder
    const auto has = [&](const char* name) {
      for (const auto& s : message_.spec->signals)
        if (s.name == name) return true;
      return false;
    };
    if (!has("v_x_mps") || !has("v_y_mps") || !has("v_z_mps")) {
      ++own_.unused;  // time, range, other devices on the bus
      return;
    }
    const auto vx = message_.value("v_x_mps"), vy = message_.value("v_y_mps"),
               vz = message_.value("v_z_mps");
    const auto bottom = message_.value("bottom_track_valid");
    if (!vx || !vy || !vz || (has("bottom_track_valid") && (!bottom || *bottom == 0.0))) {
      ++own_.invalid;
      return;
    }
    const drivers::HostTime host = message_.time.host;
    std::int64_t validity = host_validity_us(host);
    if (const auto mapped = frames_.time_of_validity_us()) {
      validity = *mapped;
      ++own_.device_clock;
    }
    DvlVelocity m;
    m.time = stamp(validity, host);
    m.v_sensor_mps = {*vx, *vy, *vz};
    out.emplace_back(m);
    ++own_.measurements;
  }

  drivers::CandumpLogDecoder candump_;
  drivers::CanFrameDecoder frames_;
  drivers::CanDecodedMessage message_;
  std::vector<drivers::CanLogFrame> log_frames_;
  std::uint64_t text_bytes_ = 0, frame_bytes_ = 0;
};

}  // namespace

std::unique_ptr<SensorDecoder> make_pd0_decoder(const SensorConfig& sensor, std::uint16_t index,
                                                const SensorDecoderOptions& options) {
  return std::make_unique<Pd0SensorDecoder>(sensor, index, options);
}
std::unique_ptr<SensorDecoder> make_pd6_decoder(const SensorConfig& sensor, std::uint16_t index) {
  return std::make_unique<Pd6SensorDecoder>(sensor, index);
}
std::unique_ptr<SensorDecoder> make_can_dvl_decoder(const SensorConfig& sensor,
                                                    std::uint16_t index) {
  return std::make_unique<CanDvlSensorDecoder>(sensor, index);
}

}  // namespace nav::daemon::detail
