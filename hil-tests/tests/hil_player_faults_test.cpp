// The HIL player's sensor faults (player_faults.h): the byte transforms checked with the
// drivers' own decoders, and a kUnplug fault played into a pty: the reader sees the line hang
// up and finds a new pty under the same symlink after the window.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <thread>

#include "nav/drivers/codecs/nmea.h"
#include "nav/drivers/codecs/paroscientific.h"
#include "nav/drivers/codecs/pd0.h"
#include "nav/drivers/codecs/seawater.h"
#include "nav/hil/dive_player.h"
#include "nav/hil/player_faults.h"
#include "support/sim_dive.h"

namespace {

using nav::hil::FaultKind;
using nav::hil::PlayerFault;
namespace drv = nav::drivers;

std::vector<std::uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

drv::Pd0Ensemble ensemble_with_bottom_track() {
  drv::Pd0Ensemble e;
  e.fixed.coord_transform = 0x1F;  // ship frame, tilts, 3-beam, mapping
  e.time.sensor_time_us = 1'700'000'000'000'000;
  e.heading_rad = 1.0;
  e.pitch_rad = 0.01;
  e.roll_rad = -0.02;
  e.depth_m = 3790.0;
  e.bottom_track.emplace();
  e.bottom_track->velocity_mps = {0.5, -0.1, 0.02, 0.0};
  e.bottom_track->range_m = {4.1, 4.2, 4.0, 4.1};
  return e;
}

TEST(PlayerFaults, GarbageVelocityDecodesWithAValidChecksumAndOnlyTheVelocitiesChanged) {
  const std::vector<std::uint8_t> original = drv::encode_pd0(ensemble_with_bottom_track());
  const auto changed = nav::hil::pd0_with_garbage_velocity(original, 2.0, 11);
  ASSERT_TRUE(changed);
  drv::Pd0Decoder decoder;
  std::vector<drv::Pd0Ensemble> out;
  decoder.feed(*changed, drv::HostTime{}, out);
  ASSERT_EQ(out.size(), 1u);  // the checksum is valid
  EXPECT_EQ(decoder.stats().checksum_failures, 0u);
  const drv::Pd0Ensemble& e = out.front();
  ASSERT_TRUE(e.bottom_track && e.bottom_track->velocity_valid());
  int moved = 0;
  for (int b = 0; b < 4; ++b) {
    EXPECT_LE(std::abs(*e.bottom_track->velocity_mps[b]), 2.0);
    moved += std::abs(*e.bottom_track->velocity_mps[b] -
                      *ensemble_with_bottom_track().bottom_track->velocity_mps[b]) > 1e-3;
    EXPECT_NEAR(*e.bottom_track->range_m[b], *ensemble_with_bottom_track().bottom_track->range_m[b],
                0.01);
  }
  EXPECT_GE(moved, 3);
  EXPECT_NEAR(*e.heading_rad, 1.0, 1e-3);
  EXPECT_EQ(e.time.sensor_time_us, ensemble_with_bottom_track().time.sensor_time_us);
  // Another seed, other values; not a PD0 ensemble: unchanged (nullopt).
  EXPECT_NE(*nav::hil::pd0_with_garbage_velocity(original, 2.0, 12), *changed);
  EXPECT_FALSE(nav::hil::pd0_with_garbage_velocity(bytes_of("$HEHDT,1.0,T*00\r\n"), 2.0, 1));
  std::vector<std::uint8_t> truncated(original.begin(), original.end() - 5);
  EXPECT_FALSE(nav::hil::pd0_with_garbage_velocity(truncated, 2.0, 1));
}

TEST(PlayerFaults, StuckHeadingRewritesHdtOnly) {
  drv::NmeaHeading h;
  h.heading_rad = 10.0 * M_PI / 180.0;
  const auto hdt = bytes_of(drv::encode_nmea(h));
  const auto changed = nav::hil::nmea_with_heading(hdt, 45.0 * M_PI / 180.0);
  ASSERT_TRUE(changed);
  drv::NmeaDecoder decoder;
  std::vector<drv::NmeaRecord> out;
  decoder.feed(*changed, drv::HostTime{}, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_NEAR(std::get<drv::NmeaHeading>(out.front()).heading_rad, 45.0 * M_PI / 180.0, 1e-4);
  drv::NmeaAttitude a;
  a.roll_rad = 0.01;
  EXPECT_FALSE(nav::hil::nmea_with_heading(bytes_of(drv::encode_nmea(a)), 1.0));
  // Through apply_fault an attitude sentence passes unchanged.
  const PlayerFault stuck{FaultKind::kHeadingStuck, "heading", 0, 1, 1.0};
  const auto att = bytes_of(drv::encode_nmea(a));
  EXPECT_EQ(nav::hil::apply_fault(stuck, att, 0), att);
}

TEST(PlayerFaults, DepthSpikesAlternateByTenMetresOfUnesco1983Depth) {
  const double lat = 41.73 * M_PI / 180.0;
  drv::ParoRecord r;
  r.pressure_pa = 3.8e7 + 101325.0;
  const auto reply = bytes_of(drv::encode_paro_reply(r));
  const PlayerFault spike{FaultKind::kDepthSpike, "depth", 0, 1, 10.0};
  auto depth_of = [&](const std::vector<std::uint8_t>& b) {
    drv::ParoDecoder decoder;
    std::vector<drv::ParoRecord> out;
    decoder.feed(b, drv::HostTime{}, out);
    EXPECT_EQ(out.size(), 1u);
    return drv::unesco1983_depth_m((out.at(0).pressure_pa - 101325.0) * 1e-4, lat);
  };
  const double base = depth_of(reply);
  const double deeper = depth_of(nav::hil::apply_fault(spike, reply, 0)) - base;
  const double shallower = depth_of(nav::hil::apply_fault(spike, reply, 1)) - base;
  // Surface density x g: 9.80 m at 3,800 m (player_faults.h)
  EXPECT_NEAR(deeper, 9.80, 0.02);
  EXPECT_NEAR(shallower, -9.80, 0.02);
  EXPECT_TRUE(
      nav::hil::apply_fault(PlayerFault{FaultKind::kDrop, "depth", 0, 1, 0}, reply, 0).empty());
}

TEST(PlayerFaults, ValidateNamesTheBadWindow) {
  EXPECT_EQ(PlayerFault({FaultKind::kDrop, "dvl", 1, 2, 0}).validate(), "");
  EXPECT_NE(PlayerFault({FaultKind::kDrop, "dvl", 2, 2, 0}).validate().find("window"),
            std::string::npos);
  EXPECT_NE(PlayerFault({FaultKind::kDrop, "", 1, 2, 0}).validate().find("no sensor"),
            std::string::npos);
  EXPECT_NE(PlayerFault({FaultKind::kGarbage, "dvl", 1, 2, 0}).validate().find("value"),
            std::string::npos);
  nav::hil::PlayerOptions o;
  o.faults.push_back({FaultKind::kUnplug, "dvl", 3, 1, 0});
  EXPECT_NE(o.validate(), "");
}

/// Reads the pty behind `link` until stopped: bytes before / after a hang-up, hang-ups seen.
struct LinkReader {
  std::filesystem::path link;
  std::atomic<bool> stop{false};
  std::atomic<int> hangups{0};
  std::atomic<long> bytes_before{0}, bytes_after{0};
  void run() {
    int fd = -1;
    while (!stop.load()) {
      if (fd < 0) fd = ::open(link.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK);
      if (fd < 0) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        continue;
      }
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      char buf[512];
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n > 0) {
        (hangups.load() == 0 ? bytes_before : bytes_after) += n;
      } else if (n == 0 || errno == EIO) {
        ++hangups;
        ::close(fd);
        fd = -1;
      }
    }
    if (fd >= 0) ::close(fd);
  }
};

TEST(PlayerFaults, UnplugHangsThePtyUpAndPlugsANewOneInAfterTheWindow) {
  const auto dir = nav::sim::test::scratch_dir("player_unplug");
  nav::sim::SimOptions so = nav::sim::test::sim_options(dir / "dive", 5, 3);  // ~27 s
  (void)nav::sim::simulate_dive(so, nav::sim::test::sim_config_path().string());
  nav::hil::PlayerOptions po;
  po.speed = 5.0;
  po.serial_dir = dir / "tty";
  po.fake_gige_camera = false;
  po.wait_for_readers = false;
  po.faults.push_back({FaultKind::kUnplug, "depth", 5.0, 10.0, 0});
  nav::hil::DivePlayer player(dir / "dive", po);
  LinkReader reader;
  reader.link = dir / "tty" / "depth";
  std::thread t([&] { reader.run(); });
  std::atomic<bool> stop{false};
  const nav::hil::PlayReport report = player.play(stop);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  reader.stop.store(true);
  t.join();
  const nav::hil::PlayedSensor* depth = nullptr;
  for (const auto& s : report.sensors) {
    if (s.name == "depth") depth = &s;
  }
  ASSERT_NE(depth, nullptr);
  EXPECT_EQ(depth->unplugs, 1);
  EXPECT_NEAR(static_cast<double>(depth->faulted), 10.0, 1.0);  // 2 Hz x 5 s
  EXPECT_EQ(reader.hangups.load(), 1);
  EXPECT_GT(reader.bytes_before.load(), 0);
  EXPECT_GT(reader.bytes_after.load(), 0);  // the new pty under the same link
  std::filesystem::remove_all(dir);
}

}  // namespace
