#pragma once
// A minimal blocking WebSocket client over a raw TCP socket for the topside tests: it can
// speak the protocol (RFC 6455 handshake, masked client frames) and also break it on purpose
// (garbage bytes, half frames, abrupt close). Header-only; loopback only.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <optional>
#include <string>

namespace nav::tool::test {

struct WsFrame {
  int opcode = 0;  ///< 1 text, 2 binary, 8 close
  std::string payload;
};

class RawWsClient {
 public:
  explicit RawWsClient(std::uint16_t port, int rcvbuf_bytes = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    if (rcvbuf_bytes > 0) ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &rcvbuf_bytes, sizeof(int));
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    connected_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  }
  ~RawWsClient() { close(); }
  RawWsClient(const RawWsClient&) = delete;
  RawWsClient& operator=(const RawWsClient&) = delete;

  bool connected() const { return connected_; }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

  bool send_raw(const std::string& bytes) {
    return ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(bytes.size());
  }

  /// Sends an HTTP request and returns the response head (status line and headers).
  std::string http(const std::string& request_head, int timeout_ms = 2000) {
    send_raw(request_head);
    std::string head;
    while (head.find("\r\n\r\n") == std::string::npos) {
      const auto b = read_bytes(1, timeout_ms);
      if (!b) break;
      head += *b;
    }
    return head;
  }

  /// Upgrade handshake on `path`; true on "101". `subprotocol` is sent if not empty.
  bool handshake(const std::string& path, const std::string& subprotocol = "") {
    std::string req = "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\n"
                      "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                      "Sec-WebSocket-Version: 13\r\n";
    if (!subprotocol.empty()) req += "Sec-WebSocket-Protocol: " + subprotocol + "\r\n";
    return http(req + "\r\n").rfind("HTTP/1.1 101", 0) == 0;
  }

  /// A masked client frame (FIN set) with `opcode` and `payload`; `declared_length` overrides
  /// the length field (to announce more than is sent).
  static std::string frame(int opcode, const std::string& payload,
                           std::optional<std::uint64_t> declared_length = std::nullopt) {
    const std::uint64_t n = declared_length.value_or(payload.size());
    std::string f(1, static_cast<char>(0x80 | opcode));
    if (n < 126) {
      f += static_cast<char>(0x80 | n);
    } else if (n < 65536) {
      f += static_cast<char>(0x80 | 126);
      f += static_cast<char>(n >> 8);
      f += static_cast<char>(n & 0xFF);
    } else {
      f += static_cast<char>(0x80 | 127);
      for (int i = 7; i >= 0; --i) f += static_cast<char>((n >> (8 * i)) & 0xFF);
    }
    const char mask[4] = {0x12, 0x34, 0x56, 0x78};
    f.append(mask, 4);
    for (std::size_t i = 0; i < payload.size(); ++i) f += static_cast<char>(payload[i] ^ mask[i % 4]);
    return f;
  }

  bool send_text(const std::string& text) { return send_raw(frame(1, text)); }

  /// The next server frame; nullopt on timeout or when the connection ends.
  std::optional<WsFrame> read_frame(int timeout_ms = 2000) {
    const auto h = read_bytes(2, timeout_ms);
    if (!h) return std::nullopt;
    WsFrame f;
    f.opcode = (*h)[0] & 0x0F;
    std::uint64_t n = static_cast<std::uint8_t>((*h)[1]) & 0x7F;
    const int ext = n == 126 ? 2 : n == 127 ? 8 : 0;
    if (ext > 0) {
      const auto e = read_bytes(ext, timeout_ms);
      if (!e) return std::nullopt;
      n = 0;
      for (char c : *e) n = (n << 8) | static_cast<std::uint8_t>(c);
    }
    const auto p = read_bytes(n, timeout_ms);
    if (!p) return std::nullopt;
    f.payload = *p;
    return f;
  }

 private:
  std::optional<std::string> read_bytes(std::size_t n, int timeout_ms) {
    std::string out;
    while (out.size() < n) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, timeout_ms) <= 0) return std::nullopt;
      char buf[65536];
      const std::size_t want = std::min(n - out.size(), sizeof buf);
      const ssize_t r = ::recv(fd_, buf, want, 0);
      if (r <= 0) return std::nullopt;
      out.append(buf, static_cast<std::size_t>(r));
    }
    return out;
  }

  int fd_ = -1;
  bool connected_ = false;
};

}  // namespace nav::tool::test
