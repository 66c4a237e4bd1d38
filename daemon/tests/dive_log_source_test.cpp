// The dive-log source: a small dive written here with DiveLogWriter and the drivers' encoders
// comes out of the queue as the right measurements, in order, with the right validity times;
// pacing at speed 10 takes about a tenth of the log's span; as fast as possible throttles at
// half the queue instead of dropping; unknown devices are counted, not fatal.
#include "nav/daemon/sources/dive_log_source.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "nav/daemon/log/dive_log.h"
#include "nav/drivers/codecs/altimeter.h"
#include "nav/drivers/codecs/nmea.h"
#include "nav/drivers/codecs/paroscientific.h"
#include "nav/drivers/codecs/pd0.h"

namespace nav::daemon {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr std::int64_t kMono0 = 1'000'000'000;  // hil-tests/README.md "Clocks"
constexpr std::int64_t kRealtimeOffset = 1086048000000000 - kMono0;

std::string temp_log(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          (name + "_" + std::to_string(::getpid()) + ".lcmlog"))
      .string();
}

SensorConfig sensor(const char* name, SensorType type, double latency_s) {
  static const std::string kPrefix;  // (GCC 12 -Wrestrict false positive on literal assignment)
  SensorConfig s;
  s.name = kPrefix + name;
  s.type = type;
  s.latency_s = latency_s;
  return s;
}

NavdConfig dive_config() {
  NavdConfig c;
  c.sensors.push_back(sensor("dvl", SensorType::kDvlPd0, 0.1));
  c.sensors.push_back(sensor("heading", SensorType::kHeadingNmea, 0.02));
  c.sensors.push_back(sensor("depth", SensorType::kPressureParo, 0.05));
  c.sensors.push_back(sensor("altimeter", SensorType::kAltimeter, 0.05));
  c.sensors.push_back(sensor("camera", SensorType::kCameraGige, 0.0));
  return c;
}

std::vector<std::uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

drivers::Pd0Ensemble ensemble(double u_mps, std::int64_t rtc_us) {
  drivers::Pd0Ensemble e;
  e.time.sensor_time_us = rtc_us;
  e.fixed.num_beams = 4;
  e.fixed.num_cells = 1;
  e.fixed.coord_transform = 1 << 3;  // instrument
  e.heading_rad = 0.0;
  e.pitch_rad = 0.0;
  e.roll_rad = 0.0;
  e.temperature_c = 2.0;
  e.salinity_ppt = 35.0;
  e.sound_speed_mps = 1480.0;
  e.depth_m = 10.0;
  drivers::Pd0BottomTrack bt;
  bt.velocity_mps = {-u_mps, 0.0, 0.0, 0.0};  // the bottom moves backwards past the DVL
  bt.range_m = {3.0, 3.0, 3.0, 3.0};
  e.bottom_track = bt;
  return e;
}

/// What the test dive should produce, in log order.
struct Expected {
  std::size_t variant_index;
  std::int64_t validity_us;
};

/// A dive of `seconds`: DVL 5 Hz (RTC 0.3 s ahead, no jitter), HDT + PHTRO 10 Hz, depth 2 Hz,
/// altimeter 5 Hz, an image each second, a registration per image pair, and one message from a
/// device the config does not know. Returns what must come out.
std::vector<Expected> write_dive(const std::string& path, int seconds) {
  DiveLogWriter w(path);
  std::vector<Expected> out;
  auto raw = [&](const char* name, std::int64_t mono, const std::vector<std::uint8_t>& b) {
    w.write_raw(name, mono + kRealtimeOffset, mono, b);
  };
  for (int tick = 0; tick < seconds * 10; ++tick) {  // 100 ms ticks of true validity time
    const std::int64_t t = kMono0 + std::int64_t{tick} * 100'000;
    if (tick % 10 == 0) {
      navlcm::image_metadata_t image{};
      image.utime = t + 1000 + kRealtimeOffset;
      image.time_of_validity_us = t;
      image.frame_id = tick / 10;
      image.state_id = -1;
      w.write(image);
      out.push_back({5, t});
      if (tick >= 10) {
        navlcm::registration_t r{};
        r.utime = image.utime;
        r.frame_id_i = tick / 10 - 1;
        r.frame_id_j = tick / 10;
        r.success = true;
        for (int k = 0; k < 25; k += 6) r.covariance[k] = 1e-4;  // a valid 5x5 covariance
        w.write(r);
      }
    }
    drivers::NmeaHeading hdt;
    hdt.heading_rad = 0.01 * tick;
    raw("heading", t + 20'000, bytes_of(drivers::encode_nmea(hdt)));
    out.push_back({1, t});
    drivers::NmeaAttitude phtro;
    phtro.roll_rad = 1 * kDeg;
    raw("heading", t + 20'500, bytes_of(drivers::encode_nmea(phtro)));
    out.push_back({1, t + 500});
    if (tick % 5 == 0) {
      drivers::ParoRecord p;
      p.pressure_pa = 10.1325e4 + 5e4;
      raw("depth", t + 50'000, bytes_of(drivers::encode_paro_reply(p)));
      out.push_back({3, t});
    }
    if (tick % 2 == 0) {
      drivers::AltimeterRecord a;
      a.raw_value_m = 3.0;
      raw("altimeter", t + 50'000, bytes_of(drivers::encode_altimeter(a)));
      out.push_back({4, t});
      // The DVL: host = validity + 100 ms; its RTC runs 0.3 s ahead of UTC.
      raw("dvl", t + 100'000, drivers::encode_pd0(ensemble(0.3, t + kRealtimeOffset + 300'000)));
      out.push_back({0, t});
    }
    if (tick == 7) raw("sonar", t + 60'000, bytes_of("ping\n"));
  }
  return out;
}

std::vector<Measurement> drain(MeasurementQueue& queue, const std::atomic<bool>& done) {
  std::vector<Measurement> got;
  while (true) {
    const bool finished = done.load();
    queue.pop_bulk(got, 1024);
    if (finished && queue.size() == 0) break;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  return got;
}

TEST(DiveLogSource, MeasurementsComeOutInOrderWithTheirValidityTimes) {
  const std::string path = temp_log("dive_source_order");
  const std::vector<Expected> expected = write_dive(path, 3);
  const NavdConfig config = dive_config();
  EXPECT_EQ(load_registrations(path).size(), 2u);

  MeasurementQueue queue(4096);
  std::atomic<bool> stop{false}, done{false};
  DiveLogSourceOptions options;
  options.as_fast_as_possible = true;
  const DiveLogSourceCounters c = run_dive_log_source(path, config, options, queue, stop, done);
  EXPECT_TRUE(done.load());
  std::vector<Measurement> got;
  queue.pop_bulk(got, 100000);

  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t k = 0; k < got.size(); ++k) {
    ASSERT_EQ(got[k].index(), expected[k].variant_index) << "measurement " << k;
    const std::int64_t v = validity_us(got[k]);
    if (got[k].index() == 0) {
      // DVL: host - latency (exact here) until the RTC mapping is trusted, then the RTC mapped
      // onto the host clock (+5 ms: half the RTC's 10 ms resolution).
      EXPECT_NEAR(double(v), double(expected[k].validity_us), 5'001.0) << k;
    } else {
      EXPECT_EQ(v, expected[k].validity_us) << "measurement " << k;
    }
  }
  const auto& dvl = std::get<DvlVelocity>(got[5]);
  EXPECT_NEAR(dvl.v_sensor_mps[0], 0.3, 1e-9);
  EXPECT_EQ(dvl.time.sensor_index, 0);
  const auto& image = std::get<ImageEvent>(got[0]);
  EXPECT_EQ(image.frame_id, 0u);
  EXPECT_EQ(image.time.sensor_index, 4);
  EXPECT_EQ(image.time.host_monotonic_us, kMono0);  // no RAW_* yet: its validity
  for (const Measurement& m : got) {
    const auto* later = std::get_if<ImageEvent>(&m);
    if (later == nullptr || later->frame_id == 0) continue;
    // utime minus the realtime - monotonic offset of the RAW_* messages before it.
    EXPECT_EQ(later->time.host_monotonic_us,
              kMono0 + std::int64_t(later->frame_id) * 1'000'000 + 1000);
  }
  EXPECT_EQ(std::get<Depth>(got[3]).time.sensor_index, 2);
  EXPECT_NEAR(std::get<Depth>(got[3]).depth_m, 4.96, 0.02);  // 5 dbar of sea water

  EXPECT_EQ(c.measurements, expected.size());
  EXPECT_EQ(c.images, 3u);
  EXPECT_EQ(c.registrations, 2u);
  EXPECT_EQ(c.unknown_devices, 1u);
  EXPECT_EQ(c.decode_errors, 0u);
  EXPECT_EQ(c.queue_drops, 0u);
  EXPECT_EQ(c.first_monotonic_us, kMono0);  // the first image's host time
  EXPECT_EQ(c.last_monotonic_us, kMono0 + 2'900'000 + 20'500);
  EXPECT_EQ(c.sensors[0].messages, 15u);
  EXPECT_GT(c.sensors[0].device_clock, 5u);
  EXPECT_EQ(c.sensors[1].measurements, 60u);
  std::remove(path.c_str());
}

TEST(DiveLogSource, SpeedTenTakesATenthOfTheLogSpan) {
  const std::string path = temp_log("dive_source_speed");
  write_dive(path, 3);
  MeasurementQueue queue(4096);
  std::atomic<bool> stop{false}, done{false};
  DiveLogSourceOptions options;
  options.speed = 10.0;
  const auto start = std::chrono::steady_clock::now();
  const DiveLogSourceCounters c =
      run_dive_log_source(path, dive_config(), options, queue, stop, done);
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double span_s = double(c.last_monotonic_us - c.first_monotonic_us) * 1e-6;
  std::printf("log span %.3f s played at speed 10 in %.3f s\n", span_s, wall_s);
  EXPECT_GT(wall_s, 0.9 * span_s / 10.0);
  EXPECT_LT(wall_s, 3.0 * span_s / 10.0 + 0.2);  // loose: a loaded 2-core machine
  std::remove(path.c_str());
}

TEST(DiveLogSource, AsFastAsPossibleThrottlesAtHalfTheQueueWithoutDrops) {
  const std::string path = temp_log("dive_source_throttle");
  const std::size_t expected = write_dive(path, 3).size();
  MeasurementQueue queue(16);
  std::atomic<bool> stop{false}, done{false};
  DiveLogSourceOptions options;
  options.as_fast_as_possible = true;
  DiveLogSourceCounters c;
  std::thread source(
      [&] { c = run_dive_log_source(path, dive_config(), options, queue, stop, done); });
  const std::vector<Measurement> got = drain(queue, done);
  source.join();
  EXPECT_EQ(got.size(), expected);
  EXPECT_EQ(c.queue_drops, 0u);
  EXPECT_EQ(queue.total_dropped(), 0u);
  std::remove(path.c_str());
}

TEST(DiveLogSource, StopEndsThePlaybackAndSetsDone) {
  const std::string path = temp_log("dive_source_stop");
  write_dive(path, 3);
  MeasurementQueue queue(4096);
  std::atomic<bool> stop{false}, done{false};
  DiveLogSourceOptions options;
  options.speed = 1.0;  // 3 s of log
  std::thread source([&] { run_dive_log_source(path, dive_config(), options, queue, stop, done); });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const auto t0 = std::chrono::steady_clock::now();
  stop.store(true);
  source.join();
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 0.5);
  EXPECT_TRUE(done.load());
  EXPECT_LT(queue.size(), 100u);  // stopped early: far from the 193 measurements of the log
  std::remove(path.c_str());
}

TEST(DiveLogSource, MissingLogAndBadSpeedAreErrors) {
  MeasurementQueue queue(8);
  std::atomic<bool> stop{false}, done{false};
  EXPECT_THROW(
      run_dive_log_source("/nonexistent/dive.lcmlog", dive_config(), {}, queue, stop, done),
      DiveLogError);
  EXPECT_TRUE(done.load());
  EXPECT_THROW(load_registrations("/nonexistent/dive.lcmlog"), DiveLogError);
  const std::string path = temp_log("dive_source_badspeed");
  write_dive(path, 1);
  DiveLogSourceOptions bad;
  bad.speed = 0.0;
  EXPECT_THROW(run_dive_log_source(path, dive_config(), bad, queue, stop, done),
               std::invalid_argument);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace nav::daemon
