#pragma once
// TopsideServer: HTTP + WebSocket on one port (websocketpp over standalone asio, one I/O
// thread). Read-only: it serves the bundled web page (GET of files in web_root), GET /stats,
// the page's feed on ws://ADDR:PORT/ws (text frames {"channel": C, "msg": {...}}), and Foxglove
// ws-protocol v1 clients (subprotocol foxglove.websocket.v1, any path). Nothing a client sends
// reaches LCM or navd.
//
// Flow control: publish_*() (any thread, typically the LCM thread) only appends to each
// client's bounded ClientQueue under a mutex and wakes the I/O thread; the I/O thread hands
// frames to a connection only while that connection's unsent bytes are below
// max_buffered_bytes. A stalled client therefore fills its own queue, whose oldest frames are
// dropped and counted, and never delays the others or the publisher.
// Bad input: a message over max_message_bytes (close 1009), a frame that is not a WebSocket
// frame (protocol error), text that is not a JSON object or an unknown request (close 1007 /
// 1008), binary data from a view client: each closes that client only.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "nav/daemon/topside/foxglove.h"

namespace nav::daemon::topside {

struct ServerOptions {
  std::string address = "127.0.0.1";
  std::uint16_t port = 8765;  ///< 0: an ephemeral port (see TopsideServer::port())
  std::filesystem::path web_root;  ///< folder of index.html, app.js, app.css
  std::size_t queue_capacity = 256;          ///< frames per client
  std::size_t max_message_bytes = 64 * 1024;  ///< largest frame a client may send
  std::size_t max_buffered_bytes = 512 * 1024;  ///< unsent bytes per connection before queueing
};

struct ServerStats {
  std::uint64_t clients = 0;             ///< connected WebSocket clients (view + Foxglove)
  std::uint64_t frames_sent = 0;
  std::uint64_t frames_dropped = 0;      ///< oldest frames dropped from full client queues
  std::uint64_t clients_closed_bad_input = 0;
};

class TopsideServer {
 public:
  explicit TopsideServer(ServerOptions options);
  ~TopsideServer();
  TopsideServer(const TopsideServer&) = delete;
  TopsideServer& operator=(const TopsideServer&) = delete;

  /// Binds and starts the I/O thread; throws std::runtime_error naming the address on failure.
  void start();
  /// Closes every connection and joins the I/O thread (idempotent).
  void stop();
  /// The bound port (after start()).
  std::uint16_t port() const;

  /// Sends {"channel": channel, "msg": msg} to every view client. A non-empty `retain_key`
  /// keeps the frame (latest per key, at most kMaxRetained keys) for clients that connect later.
  void publish_view(const std::string& channel, const nlohmann::json& msg,
                    const std::string& retain_key);
  /// Sends `msg` (JSON) on Foxglove channel `channel_id` to the clients subscribed to it.
  void publish_foxglove(std::uint32_t channel_id, std::uint64_t log_time_ns,
                        const nlohmann::json& msg);

  ServerStats stats() const;

  static constexpr std::size_t kMaxRetained = 20000;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace nav::daemon::topside
