// The device threads' health board: which sensors a snapshot reports, their record rate over
// the snapshot period, last-message age and reconnect count.
#include "nav/daemon/sources/sensor_health.h"

#include <gtest/gtest.h>

#include <string>

#include "nav/daemon/config/config.h"

namespace nav::daemon {
namespace {

SensorConfig sensor(const std::string& name, SensorType type) {
  SensorConfig s;
  s.name = name;
  s.type = type;
  return s;
}

TEST(SensorHealthBoard, SnapshotReportsActiveSensorsWithRates) {
  NavdConfig config;
  config.sensors.push_back(sensor("dvl", SensorType::kDvlPd0));
  config.sensors.push_back(sensor("depth", SensorType::kPressureParo));
  SensorHealthBoard board(config);
  board.at(1).active = true;
  board.at(1).messages = 10;
  EXPECT_EQ(board.snapshot(1'000'000).size(), 1u);
  board.at(1).messages = 30;
  board.at(1).last_message_monotonic_us = 1'500'000;
  board.at(1).reconnects = 2;
  const auto s = board.snapshot(3'000'000);
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].name, "depth");
  EXPECT_DOUBLE_EQ(s[0].rate_hz, 10.0);  // 20 records in 2 s
  EXPECT_DOUBLE_EQ(s[0].last_message_age_s, 1.5);
  EXPECT_EQ(s[0].reconnects, 2);
  EXPECT_EQ(s[0].records, 30);
}

}  // namespace
}  // namespace nav::daemon
