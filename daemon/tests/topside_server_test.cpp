// TopsideServer in process against raw WebSocket clients: the page and /stats over HTTP, bad
// input (garbage bytes, oversized, non-JSON and binary messages, half frames, abrupt
// disconnects) closes only the offending client, a stalled client's queue drops its oldest
// frames while a reading client gets the newest and the publisher never waits, and a Foxglove
// client gets serverInfo, advertise and its subscription's binary frames.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "nav/daemon/topside/server.h"
#include "support/ws_raw_client.h"

namespace nav::daemon::topside {
namespace {

namespace fs = std::filesystem;
using tool::test::RawWsClient;
using tool::test::WsFrame;

class TopsideServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    web_ = fs::temp_directory_path() / ("topside_server_" + std::to_string(::getpid()));
    fs::create_directories(web_);
    std::ofstream(web_ / "index.html") << "<html>navd</html>";
    ServerOptions o;
    o.address = "127.0.0.1";
    o.port = 0;
    o.web_root = web_;
    o.queue_capacity = 64;
    o.max_message_bytes = 1024;
    o.max_buffered_bytes = 64 * 1024;
    server_ = std::make_unique<TopsideServer>(o);
    server_->start();
    port_ = server_->port();
    ASSERT_NE(port_, 0);
  }
  void TearDown() override {
    server_->stop();
    std::error_code ignored;
    fs::remove_all(web_, ignored);
  }

  /// Publishes {"seq": n} every 200 ms until `client` reads it back; true if it did within 4 s.
  /// (A client's handshake can complete before the server has added it to its subscribers, so a
  /// single publish right after the handshake may reach nobody.)
  bool still_served(RawWsClient& client, int n) {
    const std::string wanted = "\"seq\":" + std::to_string(n) + "}";
    for (int attempt = 0; attempt < 20; ++attempt) {
      server_->publish_view("TEST", {{"seq", n}}, "");
      for (auto f = client.read_frame(200); f; f = client.read_frame(200)) {
        if (f->payload.find(wanted) != std::string::npos) return true;
      }
    }
    return false;
  }

  fs::path web_;
  std::unique_ptr<TopsideServer> server_;
  std::uint16_t port_ = 0;
};

bool closed_with(RawWsClient& c, int code) {
  for (auto f = c.read_frame(); f; f = c.read_frame()) {
    if (f->opcode == 8) {
      return f->payload.size() >= 2 && ((static_cast<std::uint8_t>(f->payload[0]) << 8) |
                                        static_cast<std::uint8_t>(f->payload[1])) == code;
    }
  }
  return false;
}

TEST_F(TopsideServerTest, ServesThePageStatsAndNothingElse) {
  RawWsClient page(port_);
  EXPECT_EQ(page.http("GET / HTTP/1.1\r\nHost: x\r\n\r\n").rfind("HTTP/1.1 200", 0), 0u);
  RawWsClient traversal(port_);
  EXPECT_EQ(
      traversal.http("GET /../etc/passwd HTTP/1.1\r\nHost: x\r\n\r\n").rfind("HTTP/1.1 404", 0),
      0u);
  RawWsClient post(port_);
  EXPECT_EQ(post.http("POST /stats HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n")
                .rfind("HTTP/1.1 405", 0),
            0u);
  RawWsClient stats(port_);
  EXPECT_EQ(stats.http("GET /stats HTTP/1.1\r\nHost: x\r\n\r\n").rfind("HTTP/1.1 200", 0), 0u);
  RawWsClient wrong_path(port_);
  EXPECT_FALSE(wrong_path.handshake("/elsewhere"));
}

TEST_F(TopsideServerTest, BadInputClosesOnlyThatClient) {
  RawWsClient good(port_);
  ASSERT_TRUE(good.handshake("/ws"));
  ASSERT_TRUE(still_served(good, 1));

  RawWsClient not_json(port_);
  ASSERT_TRUE(not_json.handshake("/ws"));
  not_json.send_text("this is not JSON {");
  EXPECT_TRUE(closed_with(not_json, 1007));

  RawWsClient oversized(port_);
  ASSERT_TRUE(oversized.handshake("/ws"));
  oversized.send_text("{\"op\":\"ping\",\"pad\":\"" + std::string(4096, 'x') + "\"}");
  EXPECT_TRUE(closed_with(oversized, 1009));

  RawWsClient binary(port_);
  ASSERT_TRUE(binary.handshake("/ws"));
  binary.send_raw(RawWsClient::frame(2, "\x01\x02\x03"));
  EXPECT_TRUE(closed_with(binary, 1003));

  RawWsClient garbage(port_);
  ASSERT_TRUE(garbage.handshake("/ws"));
  garbage.send_raw(std::string("\x0f\xff\x00\x13garbage-not-a-frame", 23));
  for (auto f = garbage.read_frame(); f; f = garbage.read_frame()) {
  }  // ends when the server drops the connection

  RawWsClient no_handshake(port_);
  no_handshake.send_raw(std::string(3000, '\x7f'));

  RawWsClient half_frame(port_);
  ASSERT_TRUE(half_frame.handshake("/ws"));
  half_frame.send_raw(RawWsClient::frame(1, "{\"op\":", 500).substr(0, 10));
  half_frame.close();  // abrupt disconnect in the middle of a frame

  RawWsClient fox_bad(port_);
  ASSERT_TRUE(fox_bad.handshake("/", kFoxgloveSubprotocol));
  fox_bad.send_text("{\"op\":\"subscribe\",\"subscriptions\":[{\"id\":\"x\"}]}");
  EXPECT_TRUE(closed_with(fox_bad, 1007));

  EXPECT_TRUE(still_served(good, 2));
  EXPECT_GE(server_->stats().clients_closed_bad_input, 3u);
}

TEST_F(TopsideServerTest, StalledClientDropsOldestWithoutDelayingOthersOrThePublisher) {
  RawWsClient stalled(port_, 4096);
  ASSERT_TRUE(stalled.handshake("/ws"));
  RawWsClient reader(port_);
  ASSERT_TRUE(reader.handshake("/ws"));
  ASSERT_TRUE(still_served(reader, -1));  // both clients are subscribers before the burst
  for (int i = 0; i < 100 && server_->stats().clients < 2; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_EQ(server_->stats().clients, 2u);
  std::atomic<int> last_seen{-1};
  std::thread read_thread([&] {
    for (auto f = reader.read_frame(); f; f = reader.read_frame()) {
      const auto at = f->payload.find("\"seq\":");
      if (at != std::string::npos) last_seen = std::stoi(f->payload.substr(at + 6));
      if (last_seen == 4999) break;
    }
  });
  const std::string pad(2000, 'p');
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 5000; ++i) server_->publish_view("TEST", {{"pad", pad}, {"seq", i}}, "");
  const double publish_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  read_thread.join();
  EXPECT_EQ(last_seen.load(), 4999);
  EXPECT_LT(publish_s, 2.0) << "the publisher waited for a client";
  EXPECT_GT(server_->stats().frames_dropped, 0u) << "the stalled client's queue never overflowed";
  std::printf("5000 frames of 2 kB published in %.3f s; %llu dropped\n", publish_s,
              static_cast<unsigned long long>(server_->stats().frames_dropped));
}

TEST_F(TopsideServerTest, FoxgloveClientGetsInfoAdvertiseAndSubscribedFrames) {
  RawWsClient fox(port_);
  ASSERT_TRUE(fox.handshake("/", kFoxgloveSubprotocol));
  const auto info = fox.read_frame();
  ASSERT_TRUE(info);
  EXPECT_EQ(nlohmann::json::parse(info->payload)["op"], "serverInfo");
  const auto adv = fox.read_frame();
  ASSERT_TRUE(adv);
  EXPECT_EQ(nlohmann::json::parse(adv->payload)["channels"].size(), foxglove_channels().size());
  fox.send_text(R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":1}]})");
  std::optional<WsFrame> f;
  for (int i = 0; i < 50 && !f; ++i) {
    server_->publish_foxglove(2, 5, {{"not", "subscribed"}});
    server_->publish_foxglove(1, 0x0102030405060708ull, {{"a", 1}});
    f = fox.read_frame(100);
  }
  ASSERT_TRUE(f);
  EXPECT_EQ(f->opcode, 2);
  EXPECT_EQ(f->payload, message_data_frame(7, 0x0102030405060708ull, "{\"a\":1}"));
}

}  // namespace
}  // namespace nav::daemon::topside
