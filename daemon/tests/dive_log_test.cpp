#include "nav/daemon/log/dive_log.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

namespace nav::daemon {
namespace {

std::string temp_log(const char* name) {
  return (std::filesystem::temp_directory_path() /
          (std::string(name) + "_" + std::to_string(::getpid()) + ".lcmlog"))
      .string();
}

TEST(DiveLog, RawChannelIsPrefixedAndUpperCased) {
  EXPECT_EQ(raw_channel("dvl"), "RAW_DVL");
  EXPECT_EQ(raw_channel("fog_1"), "RAW_FOG_1");
}

TEST(DiveLog, RoundTripsEveryEventTypeInOrder) {
  const std::string path = temp_log("dive_roundtrip");
  {
    DiveLogWriter writer(path);
    const std::vector<std::uint8_t> bytes{0x7f, 0x7f, 0x00, 0xff};
    writer.write_raw("dvl", 1000, 10, bytes);
    navlcm::image_metadata_t image{};
    image.utime = 2000;
    image.time_of_validity_us = 1990;
    image.frame_id = 7;
    image.file_path = "images/000007.png";
    writer.write(image);
    navlcm::registration_t reg{};
    reg.utime = 3000;
    reg.frame_id_i = 3;
    reg.frame_id_j = 7;
    reg.success = true;
    reg.measurement[4] = 0.25;
    reg.covariance[24] = 1e-4;
    writer.write(reg);
    EXPECT_EQ(writer.events_written(), 3);
  }
  DiveLogReader reader(path);
  auto e1 = reader.next();
  ASSERT_TRUE(e1 && std::holds_alternative<navlcm::raw_bytes_t>(*e1));
  const auto& raw = std::get<navlcm::raw_bytes_t>(*e1);
  EXPECT_EQ(raw.device, "dvl");
  EXPECT_EQ(raw.utime, 1000);
  EXPECT_EQ(raw.host_monotonic_us, 10);
  EXPECT_EQ(raw.data, (std::vector<std::uint8_t>{0x7f, 0x7f, 0x00, 0xff}));
  auto e2 = reader.next();
  ASSERT_TRUE(e2 && std::holds_alternative<navlcm::image_metadata_t>(*e2));
  EXPECT_EQ(std::get<navlcm::image_metadata_t>(*e2).frame_id, 7);
  EXPECT_EQ(std::get<navlcm::image_metadata_t>(*e2).file_path, "images/000007.png");
  auto e3 = reader.next();
  ASSERT_TRUE(e3 && std::holds_alternative<navlcm::registration_t>(*e3));
  EXPECT_EQ(std::get<navlcm::registration_t>(*e3).frame_id_j, 7);
  EXPECT_DOUBLE_EQ(std::get<navlcm::registration_t>(*e3).measurement[4], 0.25);
  EXPECT_FALSE(reader.next().has_value());
  EXPECT_EQ(reader.events_read(), 3);
  std::filesystem::remove(path);
}

TEST(DiveLog, UnknownChannelsAreSkippedAndCounted) {
  const std::string path = temp_log("dive_skip");
  {
    DiveLogWriter writer(path);
    const char payload[4] = {1, 2, 3, 4};
    writer.write_event("NAVD_SOLUTION", 5, payload, 4);
    writer.write_raw("depth", 6, 6, std::vector<std::uint8_t>{'1'});
  }
  DiveLogReader reader(path);
  auto e = reader.next();
  ASSERT_TRUE(e && std::holds_alternative<navlcm::raw_bytes_t>(*e));
  EXPECT_EQ(reader.events_skipped(), 1);
  std::filesystem::remove(path);
}

TEST(DiveLog, WritingBackInTimeThrowsNamingTheChannel) {
  const std::string path = temp_log("dive_back");
  DiveLogWriter writer(path);
  writer.write_raw("dvl", 100, 1, std::vector<std::uint8_t>{1});
  try {
    writer.write_raw("dvl", 99, 2, std::vector<std::uint8_t>{1});
    FAIL() << "expected DiveLogError";
  } catch (const DiveLogError& e) {
    EXPECT_NE(std::string(e.what()).find("RAW_DVL"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(DiveLog, CorruptPayloadOnAKnownChannelThrows) {
  const std::string path = temp_log("dive_corrupt");
  {
    DiveLogWriter writer(path);
    const char payload[3] = {9, 9, 9};
    writer.write_event("RAW_DVL", 1, payload, 3);
  }
  DiveLogReader reader(path);
  EXPECT_THROW(reader.next(), DiveLogError);
  std::filesystem::remove(path);
}

TEST(DiveLog, MissingFileThrows) {
  EXPECT_THROW(DiveLogReader("/nonexistent/dive.lcmlog"), DiveLogError);
}

}  // namespace
}  // namespace nav::daemon
