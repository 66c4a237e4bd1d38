// Sensor decoders (nav/daemon/sources/sensor_decoder.h): bytes from the drivers' encoders (and
// the real PD0 recordings) -> Measurements, with any chunking, garbage between records, the
// right flags, signs and times of validity, and counters for what was not usable.
#include "nav/daemon/sources/sensor_decoder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "nav/drivers/codecs/altimeter.h"
#include "nav/drivers/codecs/can_signals.h"
#include "nav/drivers/codecs/kvh.h"
#include "nav/drivers/codecs/nmea.h"
#include "nav/drivers/codecs/paroscientific.h"
#include "nav/drivers/codecs/pd0.h"
#include "nav/drivers/codecs/pd6.h"
#include "nav/drivers/codecs/seawater.h"
#include "nav/drivers/config/can_config.h"
#include "nav/testing/data.h"

namespace nav::daemon {
namespace {

using Bytes = std::vector<std::uint8_t>;
constexpr double kDeg = std::numbers::pi / 180.0;
constexpr std::int64_t kRealtimeOffsetUs = 1086048000000000 - 1000000000;  // sim dive clocks

Bytes bytes_of(const std::string& s) { return Bytes(s.begin(), s.end()); }
void append(Bytes& a, const Bytes& b) { a.insert(a.end(), b.begin(), b.end()); }
void append(Bytes& a, const std::string& b) { a.insert(a.end(), b.begin(), b.end()); }
const Bytes kGarbage = bytes_of("\x7f\x7f junk $GP*ZZ\r\n:BX,1\n*99\r\nm 12.3");

SensorConfig sensor_of(SensorType type, double latency_s) {
  static const std::string kName = "sensor";
  SensorConfig s;
  s.name = kName;
  s.type = type;
  s.latency_s = latency_s;
  return s;
}

/// Feeds `stream` as two reads split at `split` (host times t1, t2).
std::vector<Measurement> feed_split(SensorDecoder& d, const Bytes& stream, std::size_t split,
                                    std::int64_t t1_us, std::int64_t t2_us) {
  std::vector<Measurement> out;
  const std::span<const std::uint8_t> all(stream);
  d.feed(all.first(split), t1_us + kRealtimeOffsetUs, t1_us, out);
  d.feed(all.subspan(split), t2_us + kRealtimeOffsetUs, t2_us, out);
  return out;
}

/// For every split of `stream`, a fresh decoder must produce `expected` measurements of type M
/// (checked by `check(k, m)`) valid at t1 - latency or t2 - latency.
template <typename M, typename Check>
void expect_every_split(const SensorConfig& sensor, const Bytes& stream, std::size_t expected,
                        Check check) {
  const std::int64_t t1 = 5'000'000, t2 = 5'100'000;
  const std::int64_t lat = std::llround(sensor.latency_s * 1e6);
  for (std::size_t split = 0; split <= stream.size(); ++split) {
    auto d = make_sensor_decoder(sensor, 3);
    const std::vector<Measurement> out = feed_split(*d, stream, split, t1, t2);
    ASSERT_EQ(out.size(), expected) << "split at byte " << split;
    for (std::size_t k = 0; k < out.size(); ++k) {
      const M* m = std::get_if<M>(&out[k]);
      ASSERT_NE(m, nullptr) << "split " << split << " measurement " << k;
      EXPECT_EQ(m->time.sensor_index, 3);
      EXPECT_TRUE(m->time.validity_us == t1 - lat || m->time.validity_us == t2 - lat);
      EXPECT_EQ(m->time.host_realtime_us - m->time.host_monotonic_us, kRealtimeOffsetUs);
      EXPECT_EQ(m->time.validity_us, m->time.host_monotonic_us - lat);
      check(k, *m);
    }
    EXPECT_EQ(d->counters().bytes, stream.size());
    EXPECT_EQ(d->counters().measurements, expected);
  }
}

drivers::Pd0Ensemble pd0_ensemble(std::array<std::optional<double>, 4> bottom_mps,
                                  std::optional<std::int64_t> rtc_us, std::uint8_t frame = 1) {
  drivers::Pd0Ensemble e;
  e.ensemble_number = 7;
  e.time.sensor_time_us = rtc_us;
  e.fixed.num_beams = 4;
  e.fixed.num_cells = 1;
  e.fixed.pings_per_ensemble = 1;
  e.fixed.coord_transform = static_cast<std::uint8_t>(frame << 3);
  e.heading_rad = 10 * kDeg;
  e.pitch_rad = 1 * kDeg;
  e.roll_rad = -1 * kDeg;
  e.temperature_c = 2.0;
  e.salinity_ppt = 35.0;
  e.sound_speed_mps = 1480.0;
  e.depth_m = 3800.0;
  drivers::Pd0BottomTrack bt;
  bt.pings_per_ensemble = 1;
  bt.velocity_mps = bottom_mps;
  bt.range_m = {3.5, 3.6, 3.4, 3.5};
  e.bottom_track = bt;
  return e;
}

TEST(SensorDecoder, CamerasHaveNoByteDecoder) {
  EXPECT_FALSE(has_sensor_decoder(SensorType::kCameraGige));
  EXPECT_TRUE(has_sensor_decoder(SensorType::kAltimeter));
  EXPECT_THROW(make_sensor_decoder(sensor_of(SensorType::kCameraV4l2, 0), 0),
               std::invalid_argument);
}

TEST(SensorDecoder, Pd0BottomTrackIsNegatedInEverySplitAndInvalidOnesAreCounted) {
  Bytes stream;
  append(stream, kGarbage);
  append(stream, drivers::encode_pd0(pd0_ensemble({0.25, -0.1, 0.02, 0.0}, std::nullopt)));
  append(stream, kGarbage);
  append(stream, drivers::encode_pd0(pd0_ensemble({std::nullopt, 0.1, 0.0, 0.0}, std::nullopt)));
  append(stream, drivers::encode_pd0(pd0_ensemble({0.3, 0.1, 0.0, 0.0}, std::nullopt, 3)));
  append(stream, drivers::encode_pd0(pd0_ensemble({-0.5, 0.2, -0.03, 0.0}, std::nullopt)));
  const SensorConfig sensor = sensor_of(SensorType::kDvlPd0, 0.1);
  expect_every_split<DvlVelocity>(sensor, stream, 2, [](std::size_t k, const DvlVelocity& m) {
    const std::array<double, 3> want =
        k == 0 ? std::array<double, 3>{-0.25, 0.1, -0.02} : std::array<double, 3>{0.5, -0.2, 0.03};
    for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(m.v_sensor_mps[i], want[i], 1e-9);
  });
  auto d = make_sensor_decoder(sensor, 0);
  std::vector<Measurement> out;
  for (std::uint8_t b : stream) d->feed({&b, 1}, kRealtimeOffsetUs, 0, out);  // byte by byte
  const SensorDecoderCounters c = d->counters();
  EXPECT_EQ(out.size(), 2u);
  EXPECT_EQ(c.messages, 4u);
  EXPECT_EQ(c.invalid, 1u);            // a beam without bottom lock
  EXPECT_EQ(c.unsupported_frame, 1u);  // earth coordinates
  EXPECT_EQ(c.device_clock, 0u);       // no RTC in these ensembles
  EXPECT_GT(c.dropped_bytes, 0u);
}

TEST(SensorDecoder, Pd0RtcIsMappedOntoTheHostClockOnceTrusted) {
  // 5 Hz ensembles; the DVL's RTC runs 0.3 s ahead of UTC, the host reads each ensemble
  // 100 ms (configured latency) + Exp(2 ms) after its time of validity.
  const SensorConfig sensor = sensor_of(SensorType::kDvlPd0, 0.1);
  SensorDecoderOptions options;
  options.min_clock_samples = 5;
  auto d = make_sensor_decoder(sensor, 0, options);
  std::mt19937_64 rng(7);
  std::exponential_distribution<double> jitter(1.0 / 2000.0);
  double max_error_us = 0.0;
  for (int k = 0; k < 300; ++k) {
    const std::int64_t valid_mono = 1'000'000'000 + std::int64_t{k} * 200'000;
    const std::int64_t rtc = valid_mono + kRealtimeOffsetUs + 300'000;
    const std::int64_t host = valid_mono + 100'000 + static_cast<std::int64_t>(jitter(rng));
    std::vector<Measurement> out;
    d->feed(drivers::encode_pd0(pd0_ensemble({0.1, 0.0, 0.0, 0.0}, rtc)), host + kRealtimeOffsetUs,
            host, out);
    ASSERT_EQ(out.size(), 1u);
    const std::int64_t validity = validity_us(out[0]);
    if (k < 4) {
      EXPECT_EQ(validity, host - 100'000) << "ensemble " << k << ": mapping not trusted yet";
      continue;
    }
    max_error_us = std::max(max_error_us, std::abs(double(validity - valid_mono)));
  }
  std::printf("PD0 RTC mapping, 100 ms + Exp(2 ms) latency: max |validity error| %.0f us\n",
              max_error_us);
  EXPECT_LT(max_error_us, 12'000.0);  // 5 ms half RTC resolution + latency envelope
  EXPECT_EQ(d->counters().device_clock, 296u);
}

TEST(SensorDecoder, RealPd0RecordingInEarthFrameGivesNoSensorFrameVelocity) {
  NAV_REQUIRE_DATA(path, "dvl/RDI_withBT.000");
  std::ifstream in(path, std::ios::binary);
  const Bytes file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto d = make_sensor_decoder(sensor_of(SensorType::kDvlPd0, 0.0), 0);
  std::vector<Measurement> out;
  for (std::size_t i = 0; i < file.size(); i += 997) {
    const std::size_t n = std::min<std::size_t>(997, file.size() - i);
    d->feed(std::span<const std::uint8_t>(file).subspan(i, n), 0, 0, out);
  }
  const SensorDecoderCounters c = d->counters();
  EXPECT_EQ(c.messages, 1721u);  // every ensemble decodes (drivers/README numbers)
  EXPECT_EQ(c.decode_errors, 0u);
  EXPECT_EQ(c.unsupported_frame, 1721u);  // dolfyn: frame of vel_bt = earth
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(c.bytes, file.size());
}

TEST(SensorDecoder, Pd6BottomTrackInstrumentLinesOnly) {
  auto line = [](drivers::Pd6Velocity v) {
    drivers::Pd6Record r;
    r.value = v;
    return drivers::encode_pd6(r);
  };
  drivers::Pd6Velocity bi;
  bi.reference = drivers::Pd6Reference::kBottom;
  bi.frame = drivers::Pd6Frame::kInstrument;
  bi.velocity_mps = {0.123, -0.045, 0.006, 0.001};
  bi.valid = true;
  drivers::Pd6Velocity bad = bi;
  bad.valid = false;
  drivers::Pd6Velocity be = bi;
  be.frame = drivers::Pd6Frame::kEarth;
  drivers::Pd6Record sa;
  sa.value = drivers::Pd6Attitude{1 * kDeg, 2 * kDeg, 3 * kDeg};
  Bytes stream;
  append(stream, drivers::encode_pd6(sa));
  append(stream, line(bi));
  append(stream, kGarbage);
  append(stream, line(bad));
  append(stream, line(be));
  const SensorConfig sensor = sensor_of(SensorType::kDvlPd6, 0.1);
  expect_every_split<DvlVelocity>(sensor, stream, 1, [](std::size_t, const DvlVelocity& m) {
    EXPECT_NEAR(m.v_sensor_mps[0], 0.123, 1e-9);  // PD6: the vehicle over the bottom, no sign flip
    EXPECT_NEAR(m.v_sensor_mps[1], -0.045, 1e-9);
    EXPECT_NEAR(m.v_sensor_mps[2], 0.006, 1e-9);
  });
  auto d = make_sensor_decoder(sensor, 0);
  feed_split(*d, stream, 17, 0, 0);
  EXPECT_EQ(d->counters().invalid, 1u);
  EXPECT_EQ(d->counters().unsupported_frame, 1u);
  EXPECT_EQ(d->counters().unused, 2u);  // :SA and the garbage's :BX
}

TEST(SensorDecoder, NmeaHeadingAndRollPitchSentencesSetTheirFlags) {
  drivers::NmeaHeading hdt;
  hdt.heading_rad = 123.456 * kDeg;
  drivers::NmeaAttitude phtro;
  phtro.roll_rad = -1.5 * kDeg;
  phtro.pitch_rad = 2.25 * kDeg;
  drivers::NmeaVelocity speed;
  Bytes stream;
  append(stream, drivers::encode_nmea(hdt));
  append(stream, kGarbage);
  append(stream, drivers::encode_nmea(phtro));
  append(stream, drivers::encode_nmea(speed));
  const SensorConfig sensor = sensor_of(SensorType::kHeadingNmea, 0.02);
  expect_every_split<Attitude>(sensor, stream, 2, [&](std::size_t k, const Attitude& a) {
    if (k == 0) {
      EXPECT_TRUE(a.has_heading);
      EXPECT_FALSE(a.has_roll_pitch);
      EXPECT_NEAR(a.heading_rad, hdt.heading_rad, 1e-6);
    } else {
      EXPECT_FALSE(a.has_heading);
      EXPECT_TRUE(a.has_roll_pitch);
      EXPECT_NEAR(a.roll_rad, phtro.roll_rad, 1e-6);
      EXPECT_NEAR(a.pitch_rad, phtro.pitch_rad, 1e-6);
    }
  });
  auto d = make_sensor_decoder(sensor, 0);
  feed_split(*d, stream, 0, 0, 0);
  EXPECT_EQ(d->counters().unused, 1u);         // PIXSE SPEED_
  EXPECT_GT(d->counters().decode_errors, 0u);  // the garbage's bad sentence
}

TEST(SensorDecoder, KvhRateIsASingleAxisAngularRate) {
  drivers::KvhRecord valid;
  valid.sensor_valid = true;
  valid.rate_radps = 0.5 * kDeg;
  drivers::KvhRecord invalid;
  Bytes stream = bytes_of(drivers::encode_kvh(valid));
  append(stream, drivers::encode_kvh(invalid));
  append(stream, drivers::encode_kvh(valid));
  const SensorConfig sensor = sensor_of(SensorType::kFogKvh, 0.001);
  expect_every_split<AngularRate>(sensor, stream, 2, [](std::size_t, const AngularRate& w) {
    EXPECT_NEAR(w.omega_sensor_radps[2], 0.5 * kDeg, 1e-7);
    EXPECT_FALSE(w.has_axis[0]);
    EXPECT_FALSE(w.has_axis[1]);
    EXPECT_TRUE(w.has_axis[2]);
  });
}

TEST(SensorDecoder, ParoPressureBecomesUnesco1983Depth) {
  SensorConfig sensor = sensor_of(SensorType::kPressureParo, 0.05);
  sensor.pressure.latitude_deg = 30.0;
  sensor.pressure.surface_pressure_dbar = 10.0;
  drivers::ParoRecord deep;
  deep.pressure_pa = (10000.0 + 10.0) * drivers::kPascalPerDecibar;  // 10000 dbar of sea water
  drivers::ParoRecord in_air;
  in_air.pressure_pa = 5.0 * drivers::kPascalPerDecibar;  // far below the surface tare
  Bytes stream = bytes_of(drivers::encode_paro_reply(deep));
  append(stream, kGarbage);
  append(stream, "\r\n");
  append(stream, drivers::encode_paro_reply(in_air));
  expect_every_split<Depth>(sensor, stream, 1, [&](std::size_t, const Depth& d) {
    EXPECT_NEAR(d.depth_m, 9712.653, 0.002);  // UNESCO 1983 check value: 10000 dbar at 30 deg
  });
  auto d = make_sensor_decoder(sensor, 0);
  feed_split(*d, stream, 3, 0, 0);
  EXPECT_EQ(d->counters().invalid, 1u);
}

TEST(SensorDecoder, AltimeterNoEchoGivesNoMeasurement) {
  drivers::AltimeterRecord r;
  r.raw_value_m = 3.42;
  drivers::AltimeterRecord none;
  none.raw_value_m = 99.99;
  Bytes stream = bytes_of(drivers::encode_altimeter(r));
  append(stream, drivers::encode_altimeter(none));
  append(stream, kGarbage);
  append(stream, "\r\n");
  append(stream, drivers::encode_altimeter(r));
  const SensorConfig sensor = sensor_of(SensorType::kAltimeter, 0.05);
  expect_every_split<Altitude>(sensor, stream, 2, [](std::size_t, const Altitude& a) {
    EXPECT_NEAR(a.altitude_m, 3.42, 1e-9);
  });
  auto d = make_sensor_decoder(sensor, 0);
  feed_split(*d, stream, 0, 0, 0);
  EXPECT_EQ(d->counters().invalid, 1u);
}

// --- DVL on CAN -------------------------------------------------------------------------------

/// The example CAN table: beside this file's checkout (__FILE__ may be relative to the build
/// directory under ccache's base_dir), else relative to the working directory (ctest: source).
std::filesystem::path can_example() {
  const std::filesystem::path rel = "config/can/dvl_fog_example.yaml";
  const auto beside = std::filesystem::path(__FILE__).parent_path().parent_path().parent_path();
  return std::filesystem::exists(beside / rel) ? beside / rel : rel;
}

SensorConfig can_sensor(double latency_s) {
  SensorConfig s = sensor_of(SensorType::kDvlCan, latency_s);
  CanTransport can;
  can.interface = "can0";
  can.signals = drivers::load_can_config_file(can_example().string());
  s.transport = can;
  return s;
}

drivers::CanFrame can_frame(const drivers::CanMessageSpec& spec,
                            std::vector<drivers::CanSignalInput> values, std::int64_t mono_us) {
  const auto data = drivers::encode_can_message(spec, values);
  EXPECT_TRUE(data.has_value());
  drivers::CanFrame f;
  f.id = spec.id;
  f.extended = spec.extended;
  f.dlc = spec.dlc;
  std::copy(data->begin(), data->end(), f.data.begin());
  f.received = drivers::HostTime{mono_us, mono_us + kRealtimeOffsetUs};
  f.kernel_realtime_us = mono_us + kRealtimeOffsetUs - 100;
  return f;
}

TEST(SensorDecoder, CanDvlFromFramesAndFromCandumpLinesAgree) {
  const SensorConfig sensor = can_sensor(0.0);
  const auto& messages = std::get<CanTransport>(sensor.transport).signals.messages;
  const auto find = [&](const char* name) -> const drivers::CanMessageSpec& {
    for (const auto& m : messages)
      if (m.name == name) return m;
    throw std::runtime_error(name);
  };
  auto frames = make_sensor_decoder(sensor, 1);
  auto text = make_sensor_decoder(sensor, 1);
  std::vector<Measurement> from_frames, from_text;
  for (int k = 0; k < 40; ++k) {
    const std::int64_t valid_mono = 2'000'000'000 + std::int64_t{k} * 200'000;
    const double seq = k % 256;
    const double bt = k == 10 ? 0.0 : 1.0;  // one ping without bottom lock
    const drivers::CanFrame time = can_frame(
        find("dvl_time"), {{"time_s", 5000.0 + k * 0.2}, {"ping_seq", seq}}, valid_mono + 900);
    const drivers::CanFrame vel = can_frame(find("dvl_velocity"),
                                            {{"v_x_mps", 0.4},
                                             {"v_y_mps", -0.05},
                                             {"v_z_mps", 0.01},
                                             {"bottom_track_valid", bt},
                                             {"ping_seq", seq}},
                                            valid_mono + 1200);
    for (const auto& f : {time, vel}) {
      frames->feed_frame(f, from_frames);
      const std::string line = can_frame_log_line(f, "can0");
      const std::size_t half = line.size() / 2;  // a line split across two reads
      text->feed(std::span(reinterpret_cast<const std::uint8_t*>(line.data()), half),
                 f.received.realtime_us, f.received.monotonic_us, from_text);
      text->feed(
          std::span(reinterpret_cast<const std::uint8_t*>(line.data()) + half, line.size() - half),
          f.received.realtime_us, f.received.monotonic_us, from_text);
    }
    if (k == 20) {
      ASSERT_FALSE(from_frames.empty());
      const auto& m = std::get<DvlVelocity>(from_frames.back());
      EXPECT_NEAR(m.v_sensor_mps[0], 0.4, 1e-3);
      EXPECT_NEAR(m.v_sensor_mps[1], -0.05, 1e-3);
      EXPECT_NEAR(m.v_sensor_mps[2], 0.01, 1e-3);
      EXPECT_EQ(m.time.sensor_index, 1);
      // Dated by dvl_time's ms counter through the clock mapping (kernel stamp 800 us late).
      EXPECT_NEAR(double(m.time.validity_us), double(valid_mono), 1'500.0);
    }
  }
  ASSERT_EQ(from_frames.size(), 39u);
  ASSERT_EQ(from_text.size(), from_frames.size());
  for (std::size_t i = 0; i < from_frames.size(); ++i) {
    EXPECT_EQ(validity_us(from_frames[i]), validity_us(from_text[i])) << i;
  }
  EXPECT_EQ(frames->counters().invalid, 1u);
  EXPECT_EQ(frames->counters().unused, 40u);  // the dvl_time frames
  EXPECT_GT(frames->counters().device_clock, 30u);
  EXPECT_EQ(text->counters().decode_errors, 0u);
  // A CAN frame given to a byte sensor is an error, not a crash.
  auto nmea = make_sensor_decoder(sensor_of(SensorType::kHeadingNmea, 0), 0);
  std::vector<Measurement> none;
  nmea->feed_frame(drivers::CanFrame{}, none);
  EXPECT_TRUE(none.empty());
  EXPECT_EQ(nmea->counters().decode_errors, 1u);
}

}  // namespace
}  // namespace nav::daemon
