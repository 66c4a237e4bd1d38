// SocketCanBus through socketpair(AF_UNIX, SOCK_SEQPACKET) carrying struct can_frame bytes
// (the receive path of a PF_CAN socket: framing, filters, error frames, timestamps), and on a
// real SocketCAN interface where the kernel has one (skipped with the reason otherwise).

#include <gtest/gtest.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "nav/drivers/transports/can_bus.h"

namespace nav::drivers {
namespace {

using namespace std::chrono_literals;

CanFrame make_frame(uint32_t id, std::initializer_list<uint8_t> bytes, bool extended = false) {
  CanFrame f;
  f.id = id;
  f.extended = extended;
  f.dlc = static_cast<uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), f.data.begin());
  return f;
}

TEST(CanFilter, FollowsTheKernelMaskRule) {
  const CanFilter dvl{0x120, 0x7F0, false};  // accepts 0x120..0x12F, standard frames only
  EXPECT_TRUE(can_filter_accepts(dvl, 0x123, false));
  EXPECT_TRUE(can_filter_accepts(dvl, 0x12F, false));
  EXPECT_FALSE(can_filter_accepts(dvl, 0x133, false));
  EXPECT_FALSE(can_filter_accepts(dvl, 0x123, true));  // same number, extended format
  const CanFilter j1939{0x18FF0000, 0x1FFF0000, true};
  EXPECT_TRUE(can_filter_accepts(j1939, 0x18FF1234, true));
  EXPECT_FALSE(can_filter_accepts(j1939, 0x18FE1234, true));
  EXPECT_FALSE(can_filter_accepts(j1939, 0x0234, false));
  const CanFilter all{0, 0, false};  // mask 0 still separates formats (CAN_EFF_FLAG in mask)
  EXPECT_TRUE(can_filter_accepts(all, 0x7FF, false));
  EXPECT_FALSE(can_filter_accepts(all, 0x7FF, true));
}

TEST(CanFrameValidation, RejectsIdsBeyondTheFormatAndLongFrames) {
  EXPECT_TRUE(validate_can_frame(make_frame(0x7FF, {1})).ok());
  EXPECT_EQ(validate_can_frame(make_frame(0x800, {1})).code(), IoCode::kInvalidArgument);
  EXPECT_TRUE(validate_can_frame(make_frame(0x1FFFFFFF, {}, true)).ok());
  EXPECT_FALSE(validate_can_frame(make_frame(0x20000000, {}, true)).ok());
  CanFrame f = make_frame(0x10, {});
  f.dlc = 9;
  EXPECT_NE(validate_can_frame(f).message().find("dlc 9"), std::string::npos);
}

class CanSocketpair : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(open_can_socketpair(tx_, rx_).ok()); }
  SocketCanBus tx_;
  SocketCanBus rx_;
};

TEST_F(CanSocketpair, CarriesFramesWithKernelTimestamps) {
  const HostTime before = host_time_now();
  const CanFrame sent[] = {make_frame(0x123, {0xDE, 0xAD, 0xBE, 0xEF}),
                           make_frame(0x18FF1234, {1, 2, 3, 4, 5, 6, 7, 8}, true),
                           make_frame(0x7FF, {})};
  for (const CanFrame& f : sent) ASSERT_TRUE(tx_.send(f, 100ms).ok());
  for (const CanFrame& expected : sent) {
    CanFrame got;
    const IoStatus s = rx_.receive(got, 1s);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(got.id, expected.id);
    EXPECT_EQ(got.extended, expected.extended);
    EXPECT_EQ(got.dlc, expected.dlc);
    EXPECT_EQ(got.data, expected.data);
    ASSERT_TRUE(got.kernel_realtime_us.has_value());
    EXPECT_GE(*got.kernel_realtime_us, before.realtime_us);
    EXPECT_LE(*got.kernel_realtime_us, got.received.realtime_us);  // kernel first, then us
  }
  EXPECT_EQ(tx_.stats().frames_sent, 3u);
  EXPECT_EQ(rx_.stats().frames_received, 3u);
}

TEST_F(CanSocketpair, RemoteFramesKeepTheirFlag) {
  CanFrame rtr = make_frame(0x321, {});
  rtr.remote = true;
  rtr.dlc = 8;  // an RTR requests 8 bytes; carries none
  ASSERT_TRUE(tx_.send(rtr, 100ms).ok());
  CanFrame got;
  ASSERT_TRUE(rx_.receive(got, 1s).ok());
  EXPECT_TRUE(got.remote);
  EXPECT_EQ(got.id, 0x321u);
}

TEST_F(CanSocketpair, FiltersSkipAndCountOtherIds) {
  const CanFilter only_dvl[] = {{0x100, 0x700, false}};
  ASSERT_TRUE(rx_.set_filters(only_dvl).ok());
  for (uint32_t id : {0x123u, 0x223u, 0x1FFu})
    ASSERT_TRUE(tx_.send(make_frame(id, {7}), 100ms).ok());
  CanFrame got;
  ASSERT_TRUE(rx_.receive(got, 1s).ok());
  EXPECT_EQ(got.id, 0x123u);
  ASSERT_TRUE(rx_.receive(got, 1s).ok());
  EXPECT_EQ(got.id, 0x1FFu);
  EXPECT_EQ(rx_.stats().filtered_out, 1u);
  ASSERT_TRUE(rx_.set_filters({}).ok());  // empty list: accept all again
  ASSERT_TRUE(tx_.send(make_frame(0x223, {}), 100ms).ok());
  ASSERT_TRUE(rx_.receive(got, 1s).ok());
  EXPECT_EQ(got.id, 0x223u);
}

TEST_F(CanSocketpair, TimesOutWhenTheBusIsQuiet) {
  CanFrame got;
  EXPECT_EQ(rx_.receive(got, 30ms).code(), IoCode::kTimeout);
}

TEST_F(CanSocketpair, InvalidFrameIsRefusedAndNothingIsSent) {
  EXPECT_EQ(tx_.send(make_frame(0x800, {1}), 100ms).code(), IoCode::kInvalidArgument);
  CanFrame got;
  EXPECT_EQ(rx_.receive(got, 30ms).code(), IoCode::kTimeout);
  EXPECT_EQ(tx_.stats().frames_sent, 0u);
}

TEST_F(CanSocketpair, PeerClosingIsReportedAsDisconnected) {
  tx_.close();
  CanFrame got;
  const IoStatus s = rx_.receive(got, 1s);
  EXPECT_EQ(s.code(), IoCode::kDisconnected) << s.message();
}

TEST(CanSocketBus, CountsErrorFramesAndMalformedDatagramsThenDeliversGoodFrames) {
  int fds[2];
  ASSERT_EQ(::socketpair(AF_UNIX, SOCK_SEQPACKET, 0, fds), 0);
  SocketCanBus bus;
  ASSERT_TRUE(bus.adopt_socket(fds[0], "raw-peer").ok());
  const int peer = fds[1];
  can_frame bus_off{};
  bus_off.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  bus_off.len = CAN_ERR_DLC;
  ASSERT_EQ(::send(peer, &bus_off, sizeof bus_off, 0), static_cast<ssize_t>(sizeof bus_off));
  const uint8_t short_datagram[5] = {1, 2, 3, 4, 5};
  ASSERT_EQ(::send(peer, short_datagram, sizeof short_datagram, 0), 5);
  can_frame too_long{};
  too_long.can_id = 0x55;
  too_long.len = 12;
  ASSERT_EQ(::send(peer, &too_long, sizeof too_long, 0), static_cast<ssize_t>(sizeof too_long));
  can_frame good{};
  good.can_id = 0x42;
  good.len = 2;
  good.data[0] = 0xAB;
  good.data[1] = 0xCD;
  ASSERT_EQ(::send(peer, &good, sizeof good, 0), static_cast<ssize_t>(sizeof good));

  CanFrame got;
  ASSERT_TRUE(bus.receive(got, 1s).ok());
  EXPECT_EQ(got.id, 0x42u);
  EXPECT_EQ(got.dlc, 2);
  EXPECT_EQ(got.data[1], 0xCD);
  EXPECT_EQ(bus.stats().error_frames, 1u);
  EXPECT_EQ(bus.stats().last_error_class, static_cast<uint32_t>(CAN_ERR_BUSOFF));
  EXPECT_EQ(bus.stats().malformed, 2u);
  EXPECT_EQ(bus.stats().frames_received, 1u);
  ::close(peer);
}

TEST(CanSocketBus, ClosedBusFailsCleanly) {
  SocketCanBus bus;
  CanFrame f;
  EXPECT_EQ(bus.receive(f, 1ms).code(), IoCode::kDisconnected);
  EXPECT_EQ(bus.send(make_frame(1, {}), 1ms).code(), IoCode::kDisconnected);
  EXPECT_EQ(bus.adopt_socket(-1, "bad").code(), IoCode::kInvalidArgument);
}

// Real SocketCAN: needs a kernel with CAN and an interface (NAV_CAN_INTERFACE, default vcan0).
TEST(SocketCanReal, LoopbackOnARealInterface) {
  const char* env = std::getenv("NAV_CAN_INTERFACE");
  const std::string ifname = env != nullptr ? env : "vcan0";
  SocketCanBus a;
  const IoStatus s = a.open_interface(ifname);
  if (s.code() == IoCode::kUnsupported || s.code() == IoCode::kDisconnected) {
    GTEST_SKIP() << "no SocketCAN here: " << s.message();
  }
  ASSERT_TRUE(s.ok()) << s.message();
  SocketCanBus b;
  ASSERT_TRUE(b.open_interface(ifname).ok());
  ASSERT_TRUE(a.send(make_frame(0x2A5, {9, 8, 7}), 100ms).ok());
  CanFrame got;
  const IoStatus r = b.receive(got, 1s);
  ASSERT_TRUE(r.ok()) << r.message();
  EXPECT_EQ(got.id, 0x2A5u);
  EXPECT_TRUE(got.kernel_realtime_us.has_value());
}

}  // namespace
}  // namespace nav::drivers
