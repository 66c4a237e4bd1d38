// CAN frames from the transport decoded with the example DVL + FOG table: host time from the
// kernel stamp, sensor time counters mapped onto the monotonic clock, counters, and frames
// carried through the SocketCanBus receive path (socketpair).

#include "nav/drivers/config/can_frame_decoder.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>

#include "nav/drivers/config/can_config.h"

namespace nav::drivers {
namespace {

using namespace std::chrono_literals;

const std::string kExample =
    (std::filesystem::path(NAV_SOURCE_DIR) / "config/can/dvl_fog_example.yaml")
        .lexically_normal()
        .string();

CanFrame frame_of(const CanMessageSpec& spec, const std::vector<CanSignalInput>& values) {
  CanFrame f;
  f.id = spec.id;
  f.extended = spec.extended;
  const auto bytes = encode_can_message(spec, values);
  f.dlc = static_cast<uint8_t>(bytes->size());
  std::copy(bytes->begin(), bytes->end(), f.data.begin());
  return f;
}

TEST(CanFrameDecoder, HostTimeFromTheKernelStamp) {
  CanFrame f;
  f.received = HostTime{5'000'000, 1'700'000'000'000'000};
  EXPECT_EQ(can_frame_monotonic_us(f), 5'000'000);
  f.kernel_realtime_us = 1'700'000'000'000'000 - 300;
  EXPECT_EQ(can_frame_monotonic_us(f), 5'000'000 - 300);
  f.kernel_realtime_us = 1'700'000'000'000'000 + 10;  // after the read: not trusted
  EXPECT_EQ(can_frame_monotonic_us(f), 5'000'000);
  f.kernel_realtime_us = 1'700'000'000'000'000 - 2'000'000;  // 2 s stale: not trusted
  EXPECT_EQ(can_frame_monotonic_us(f), 5'000'000);
}

TEST(CanFrameDecoder, FogTimeCounterMapsOntoTheMonotonicClock) {
  CanFrameDecoder decoder(load_can_config_file(kExample).messages);
  const CanMessageSpec& fog_time = *decoder.signals().find("fog_time");
  const CanMessageSpec& attitude = *decoder.signals().find("fog_attitude");
  // 32-bit µs counter starting 2 s before its wrap, 80 ppm slow, 100 Hz; the frame reaches
  // the kernel 0.2 ms + Exp(1 ms) after its time of validity.
  std::mt19937_64 rng(31);
  std::exponential_distribution<double> jitter(1.0 / 1000.0);
  const double modulus = 4294967296.0;
  double max_error_us = 0.0;
  CanDecodedMessage out;
  for (int k = 0; k < 3000; ++k) {
    const int64_t t_us = 10'000'000 + int64_t{k} * 10'000;  // true monotonic time of validity
    const double sensor = std::fmod(modulus - 2e6 + (t_us - 10'000'000) * (1 - 80e-6), modulus);
    CanFrame f =
        frame_of(fog_time, {{"time_s", std::floor(sensor) / 1e6}, {"seq", double(k % 256)}});
    const int64_t kernel_mono = t_us + 200 + static_cast<int64_t>(jitter(rng));
    f.received = HostTime{kernel_mono + 50, 1'700'000'000'000'000 + kernel_mono + 50};
    f.kernel_realtime_us = 1'700'000'000'000'000 + kernel_mono;
    ASSERT_TRUE(decoder.decode(f, out));
    EXPECT_EQ(out.time.host.monotonic_us, kernel_mono);
    const std::optional<int64_t> time_of_validity = decoder.time_of_validity_us();
    // The attitude message with the same seq follows and is dated by that fog_time.
    CanFrame a = frame_of(attitude, {{"heading_rad", 1.0}, {"seq", double(k % 256)}});
    a.received = f.received;
    ASSERT_TRUE(decoder.decode(a, out));
    EXPECT_EQ(decoder.time_of_validity_us(), time_of_validity);
    if (k < 500) continue;  // first 5 s: the window fills
    ASSERT_TRUE(time_of_validity.has_value());
    max_error_us = std::max(max_error_us, std::abs(static_cast<double>(*time_of_validity - t_us)));
  }
  std::printf("FOG 32-bit us counter, 0.2 ms + Exp(1 ms) latency: max |error| %.0f us\n",
              max_error_us);
  EXPECT_LT(max_error_us, 400.0);  // the 0.2 ms latency floor is in it
  const ClockMapping* clock = decoder.clock(fog_time);
  ASSERT_NE(clock, nullptr);
  EXPECT_EQ(clock->stats().wraps, 1u);
  EXPECT_EQ(clock->stats().resets, 0u);
  EXPECT_EQ(decoder.clock(*decoder.signals().find("dvl_velocity")), nullptr);
}

TEST(CanFrameDecoder, RemoteUnknownAndShortFramesAreCounted) {
  CanFrameDecoder decoder(load_can_config_file(kExample).messages);
  CanDecodedMessage out;
  CanFrame remote;
  remote.id = 0x200;
  remote.remote = true;
  EXPECT_FALSE(decoder.decode(remote, out));
  CanFrame unknown;
  unknown.id = 0x555;
  unknown.dlc = 2;
  EXPECT_FALSE(decoder.decode(unknown, out));
  CanFrame short_frame;
  short_frame.id = 0x200;
  short_frame.dlc = 7;
  EXPECT_FALSE(decoder.decode(short_frame, out));
  const CanMessageSpec& vel = *decoder.signals().find("dvl_velocity");
  EXPECT_TRUE(decoder.decode(frame_of(vel, {{"v_x_mps", 0.25}}), out));
  EXPECT_FALSE(decoder.time_of_validity_us().has_value());  // dvl_velocity has no time signal
  EXPECT_EQ(decoder.stats().unsupported, 2u);
  EXPECT_EQ(decoder.stats().malformed, 1u);
  EXPECT_EQ(decoder.stats().records, 1u);
}

TEST(CanFrameDecoder, FramesThroughTheSocketCanReceivePath) {
  SocketCanBus tx, rx;
  ASSERT_TRUE(open_can_socketpair(tx, rx).ok());
  CanFrameDecoder decoder(load_can_config_file(kExample).messages);
  const CanMessageSpec& att = *decoder.signals().find("fog_attitude");
  const CanMessageSpec& vel = *decoder.signals().find("dvl_velocity");
  constexpr double kDeg = std::numbers::pi / 180.0;
  ASSERT_TRUE(
      tx.send(frame_of(att, {{"heading_rad", 271.5 * kDeg}, {"roll_rad", -3.25 * kDeg}}), 100ms)
          .ok());
  ASSERT_TRUE(tx.send(frame_of(vel, {{"v_x_mps", -1.5}, {"v_z_mps", 0.125}}), 100ms).ok());
  CanDecodedMessage out;
  CanFrame f;
  ASSERT_TRUE(rx.receive(f, 1000ms).ok());
  ASSERT_TRUE(decoder.decode(f, out));
  EXPECT_EQ(out.spec->name, "fog_attitude");
  EXPECT_NEAR(*out.value("heading_rad"), 271.5 * kDeg, 1e-12);
  EXPECT_NEAR(*out.value("roll_rad"), -3.25 * kDeg, 1e-12);
  EXPECT_EQ(out.time.host.monotonic_us, can_frame_monotonic_us(f));
  ASSERT_TRUE(rx.receive(f, 1000ms).ok());
  ASSERT_TRUE(decoder.decode(f, out));
  EXPECT_DOUBLE_EQ(*out.value("v_x_mps"), -1.5);
  EXPECT_DOUBLE_EQ(*out.value("v_z_mps"), 0.125);
  EXPECT_FALSE(out.value("v_y_mps").has_value());
}

}  // namespace
}  // namespace nav::drivers
