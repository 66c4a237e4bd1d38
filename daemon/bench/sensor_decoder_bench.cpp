// Throughput of navd's sensor decoders (daemon/include/nav/daemon/sources/sensor_decoder.h):
// bytes in, Measurements out, including time stamping (the PD0 RTC clock mapping). Reports
// bytes/s and measurements/s; the replay's realtime factor is bounded by these.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "nav/daemon/sources/sensor_decoder.h"
#include "nav/drivers/codecs/nmea.h"
#include "nav/drivers/codecs/paroscientific.h"
#include "nav/drivers/codecs/pd0.h"

namespace {

using namespace nav;

daemon::SensorConfig sensor(daemon::SensorType type) {
  static const std::string kName = "bench";
  daemon::SensorConfig s;
  s.name = kName;
  s.type = type;
  s.latency_s = 0.05;
  return s;
}

/// `n` chunks (one per read) and their host times, 5 Hz.
struct Stream {
  std::vector<std::vector<std::uint8_t>> chunks;
  std::size_t bytes = 0;
  void add(const std::string& s) { add(std::vector<std::uint8_t>(s.begin(), s.end())); }
  void add(std::vector<std::uint8_t> b) {
    bytes += b.size();
    chunks.push_back(std::move(b));
  }
};

void run(benchmark::State& state, const daemon::SensorConfig& config, const Stream& stream) {
  std::vector<daemon::Measurement> out;
  std::int64_t measurements = 0;
  for (auto _ : state) {
    auto decoder = daemon::make_sensor_decoder(config, 0);
    std::int64_t t = 1'000'000'000;
    for (const auto& chunk : stream.chunks) {
      out.clear();
      decoder->feed(chunk, t + 1'000'000, t, out);
      measurements += static_cast<std::int64_t>(out.size());
      t += 200'000;
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(stream.bytes));
  state.SetItemsProcessed(measurements);
}

void BM_SensorDecoderPd0(benchmark::State& state) {
  Stream stream;
  for (int k = 0; k < 1000; ++k) {
    drivers::Pd0Ensemble e;
    e.time.sensor_time_us = 1'086'048'000'000'000 + std::int64_t{k} * 200'000;
    e.fixed.num_beams = 4;
    e.fixed.coord_transform = 1 << 3;
    e.heading_rad = 0.1;
    e.pitch_rad = 0.0;
    e.roll_rad = 0.0;
    e.temperature_c = 2.0;
    e.salinity_ppt = 35.0;
    e.sound_speed_mps = 1500.0;
    e.depth_m = 3800.0;
    drivers::Pd0BottomTrack bt;
    bt.velocity_mps = {-0.3, 0.01, 0.0, 0.0};
    bt.range_m = {4.0, 4.0, 4.0, 4.0};
    e.bottom_track = bt;
    stream.add(drivers::encode_pd0(e));
  }
  run(state, sensor(daemon::SensorType::kDvlPd0), stream);
}
BENCHMARK(BM_SensorDecoderPd0);

void BM_SensorDecoderNmea(benchmark::State& state) {
  Stream stream;
  for (int k = 0; k < 1000; ++k) {
    drivers::NmeaHeading h;
    h.heading_rad = 0.001 * k;
    drivers::NmeaAttitude a;
    a.roll_rad = 0.01;
    a.pitch_rad = -0.02;
    stream.add(drivers::encode_nmea(h) + drivers::encode_nmea(a));
  }
  run(state, sensor(daemon::SensorType::kHeadingNmea), stream);
}
BENCHMARK(BM_SensorDecoderNmea);

void BM_SensorDecoderParo(benchmark::State& state) {
  Stream stream;
  for (int k = 0; k < 1000; ++k) {
    drivers::ParoRecord r;
    r.pressure_pa = 3.8e7 + k;
    stream.add(drivers::encode_paro_reply(r));
  }
  run(state, sensor(daemon::SensorType::kPressureParo), stream);
}
BENCHMARK(BM_SensorDecoderParo);

}  // namespace
