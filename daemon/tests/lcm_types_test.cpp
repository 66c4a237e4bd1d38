// The generated LCM types encode/decode losslessly and travel through a real LCM instance
// (in-process memq:// transport), including the variable-length arrays.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>

#include <navlcm/bounds_snapshot_t.hpp>
#include <navlcm/health_t.hpp>
#include <navlcm/nav_solution_t.hpp>
#include <navlcm/raw_bytes_t.hpp>

namespace {

template <typename Msg>
Msg round_trip(const Msg& msg) {
  std::vector<uint8_t> buffer(msg.getEncodedSize());
  EXPECT_EQ(msg.encode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  Msg decoded;
  EXPECT_EQ(decoded.decode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  return decoded;
}

TEST(LcmTypes, NavSolutionRoundTrip) {
  navlcm::nav_solution_t msg{};
  msg.utime = 1'700'000'000'123'456;
  msg.time_of_validity_us = 42;
  for (int k = 0; k < 36; ++k) msg.pose_covariance[k] = 0.25 * k;
  msg.p_world_m[2] = 3810.5;
  msg.filter_status = 1;
  const auto out = round_trip(msg);
  EXPECT_EQ(out.utime, msg.utime);
  EXPECT_EQ(out.p_world_m[2], 3810.5);
  EXPECT_EQ(out.pose_covariance[35], 0.25 * 35);
  EXPECT_EQ(out.filter_status, 1);
}

TEST(LcmTypes, VariableLengthArraysRoundTrip) {
  navlcm::bounds_snapshot_t snapshot{};
  snapshot.num_states = 3;
  snapshot.states.resize(3);
  for (int i = 0; i < 3; ++i) {
    snapshot.states[i].state_id = 100 + i;
    snapshot.states[i].bound_covariance[7] = 1.0 / (i + 1);
  }
  const auto out = round_trip(snapshot);
  ASSERT_EQ(out.states.size(), 3u);
  EXPECT_EQ(out.states[2].state_id, 102);
  EXPECT_DOUBLE_EQ(out.states[1].bound_covariance[7], 0.5);

  navlcm::health_t health{};
  health.num_sensors = 1;
  health.sensors.resize(1);
  health.sensors[0].name = "dvl";
  health.sensors[0].num_components = 2;
  health.sensors[0].last.resize(2);
  health.sensors[0].last[1].innovation = -0.02;
  health.status = "ok";
  const auto h = round_trip(health);
  EXPECT_EQ(h.sensors.at(0).name, "dvl");
  EXPECT_DOUBLE_EQ(h.sensors.at(0).last.at(1).innovation, -0.02);
}

class Receiver {
 public:
  void on_raw(const lcm::ReceiveBuffer*, const std::string& channel, const navlcm::raw_bytes_t* m) {
    channel_ = channel;
    received_ = *m;
  }
  std::string channel_;
  navlcm::raw_bytes_t received_{};
};

TEST(LcmTypes, RawBytesThroughMemqTransport) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good()) << "memq:// LCM could not be created";
  Receiver receiver;
  lcm.subscribe("RAW_DVL", &Receiver::on_raw, &receiver);
  navlcm::raw_bytes_t msg{};
  msg.utime = 5;
  msg.device = "dvl";
  msg.data = {0x7F, 0x7F, 0x00, 0xFF};
  msg.num_bytes = static_cast<int32_t>(msg.data.size());
  ASSERT_EQ(lcm.publish("RAW_DVL", &msg), 0);
  ASSERT_GT(lcm.handleTimeout(1000), 0) << "no message delivered within 1 s";
  EXPECT_EQ(receiver.channel_, "RAW_DVL");
  EXPECT_EQ(receiver.received_.data, msg.data);
  EXPECT_EQ(receiver.received_.device, "dvl");
}

}  // namespace
