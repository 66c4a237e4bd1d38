// websocketpp (standalone asio) server of navtool topside; the contract is in server.h.
// websocketpp 0.8.2 does not compile as C++20 (template-ids on constructors), so this one file
// is built as C++17 (daemon/CMakeLists.txt); server.h itself is plain C++17.
#include "nav/daemon/topside/server.h"

#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "nav/daemon/topside/client_queue.h"

namespace nav::daemon::topside {
namespace {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Hdl = websocketpp::connection_hdl;
namespace close_code = websocketpp::close::status;

constexpr long kFlushPeriodMs = 20;  // retries clients whose socket buffer was full

std::string dump(const nlohmann::json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string content_type(const std::string& name) {
  const auto ends = [&](const char* ext) {
    const std::string e(ext);
    return name.size() >= e.size() && name.compare(name.size() - e.size(), e.size(), e) == 0;
  };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  if (ends(".png")) return "image/png";
  return "application/octet-stream";
}

/// A file name of the web root: letters, digits, '.', '_', '-', not starting with '.'.
bool safe_file_name(const std::string& name) {
  if (name.empty() || name[0] == '.') return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-';
  });
}

struct Client {
  bool foxglove = false;
  WsServer::connection_ptr con;
  ClientQueue queue;
  std::multimap<std::uint32_t, std::uint32_t> subscription_by_channel;  // channel -> subscription
  Client(bool fox, WsServer::connection_ptr c, std::size_t capacity)
      : foxglove(fox), con(std::move(c)), queue(capacity) {}
};

}  // namespace

struct TopsideServer::Impl {
  explicit Impl(ServerOptions o) : options(std::move(o)) {}

  ServerOptions options;
  WsServer ws;
  std::thread io_thread;
  std::atomic<bool> started{false};  // publish_*() before start() only retains

  mutable std::recursive_mutex mutex;  // guards clients, retained, stats
  std::map<Hdl, std::shared_ptr<Client>, std::owner_less<Hdl>> clients;
  std::map<std::string, std::pair<std::uint64_t, std::shared_ptr<const std::string>>> retained;
  std::uint64_t retained_seq = 0;
  ServerStats stats;
  std::atomic<bool> flush_pending{false};

  void setup();
  void flush_all();
  void arm_timer();
  void wake();
  void close_bad(const std::shared_ptr<Client>& c, close_code::value code, const std::string& why);
  void on_message(Hdl hdl, WsServer::message_ptr msg);
  void on_foxglove_request(const std::shared_ptr<Client>& c, const nlohmann::json& req);
  void on_http(Hdl hdl);
};

void TopsideServer::Impl::setup() {
  ws.clear_access_channels(websocketpp::log::alevel::all);
  ws.clear_error_channels(websocketpp::log::elevel::all);
  ws.init_asio();
  ws.set_reuse_addr(true);
  ws.set_max_message_size(options.max_message_bytes);
  ws.set_max_http_body_size(options.max_message_bytes);
  // Small frames at 10 Hz: no Nagle delay (it would hold a frame until the previous is acked).
  ws.set_socket_init_handler([](Hdl, asio::ip::tcp::socket& socket) {
    asio::error_code ignored;
    socket.set_option(asio::ip::tcp::no_delay(true), ignored);
  });
  ws.set_validate_handler([this](Hdl hdl) {
    WsServer::connection_ptr con = ws.get_con_from_hdl(hdl);
    for (const std::string& p : con->get_requested_subprotocols()) {
      if (p == kFoxgloveSubprotocol) {
        con->select_subprotocol(p);
        return true;
      }
    }
    return con->get_resource() == "/ws";
  });
  ws.set_open_handler([this](Hdl hdl) {
    WsServer::connection_ptr con = ws.get_con_from_hdl(hdl);
    const bool fox = con->get_subprotocol() == kFoxgloveSubprotocol;
    std::lock_guard lock(mutex);
    clients.emplace(hdl, std::make_shared<Client>(fox, con, options.queue_capacity));
    ++stats.clients;
    if (fox) {
      con->send(dump(server_info_message("navtool topside")), websocketpp::frame::opcode::text);
      con->send(dump(advertise_message(foxglove_channels())), websocketpp::frame::opcode::text);
      return;
    }
    // The retained state (latest solution, health, every bound and link) once, oldest first.
    std::vector<std::pair<std::uint64_t, std::shared_ptr<const std::string>>> frames;
    for (const auto& [key, entry] : retained) frames.push_back(entry);
    std::sort(frames.begin(), frames.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& f : frames) con->send(*f.second, websocketpp::frame::opcode::text);
  });
  const auto gone = [this](Hdl hdl) {
    std::lock_guard lock(mutex);
    if (clients.erase(hdl) > 0) --stats.clients;
  };
  ws.set_close_handler(gone);
  ws.set_fail_handler(gone);
  ws.set_message_handler([this](Hdl hdl, WsServer::message_ptr msg) { on_message(hdl, msg); });
  ws.set_http_handler([this](Hdl hdl) { on_http(hdl); });
}

void TopsideServer::Impl::close_bad(const std::shared_ptr<Client>& c, close_code::value code,
                                    const std::string& why) {
  {
    std::lock_guard lock(mutex);
    ++stats.clients_closed_bad_input;
  }
  websocketpp::lib::error_code ec;
  c->con->close(code, why, ec);
}

void TopsideServer::Impl::on_message(Hdl hdl, WsServer::message_ptr msg) {
  std::shared_ptr<Client> c;
  {
    std::lock_guard lock(mutex);
    const auto it = clients.find(hdl);
    if (it == clients.end()) return;
    c = it->second;
  }
  if (msg->get_opcode() != websocketpp::frame::opcode::text) {
    close_bad(c, close_code::unsupported_data, "binary messages are not accepted");
    return;
  }
  const nlohmann::json req = nlohmann::json::parse(msg->get_payload(), nullptr, false);
  if (req.is_discarded() || !req.is_object() || !req.contains("op") || !req["op"].is_string()) {
    close_bad(c, close_code::invalid_payload, "expected a JSON object with a string \"op\"");
    return;
  }
  if (!c->foxglove) {
    if (req["op"] != "ping") close_bad(c, close_code::policy_violation, "the view feed is read-only");
    return;
  }
  try {
    on_foxglove_request(c, req);
  } catch (const nlohmann::json::exception& e) {
    close_bad(c, close_code::invalid_payload, std::string("malformed request: ") + e.what());
  }
}

void TopsideServer::Impl::on_foxglove_request(const std::shared_ptr<Client>& c,
                                              const nlohmann::json& req) {
  const std::string op = req.at("op").get<std::string>();
  std::lock_guard lock(mutex);
  if (op == "subscribe") {
    for (const auto& s : req.at("subscriptions")) {
      const auto channel = s.at("channelId").get<std::uint32_t>();
      const auto id = s.at("id").get<std::uint32_t>();
      const auto& known = foxglove_channels();
      if (std::none_of(known.begin(), known.end(), [&](const auto& k) { return k.id == channel; })) {
        c->con->send(dump(status_message(1, "no channel " + std::to_string(channel))),
                     websocketpp::frame::opcode::text);
        continue;
      }
      c->subscription_by_channel.emplace(channel, id);
    }
  } else if (op == "unsubscribe") {
    for (const auto& idj : req.at("subscriptionIds")) {
      const auto id = idj.get<std::uint32_t>();
      auto& subs = c->subscription_by_channel;
      for (auto it = subs.begin(); it != subs.end();) it = it->second == id ? subs.erase(it) : ++it;
    }
  } else {
    c->con->send(dump(status_message(1, "unsupported op '" + op + "' (read-only server)")),
                 websocketpp::frame::opcode::text);
  }
}

void TopsideServer::Impl::on_http(Hdl hdl) {
  WsServer::connection_ptr con = ws.get_con_from_hdl(hdl);
  con->append_header("Cache-Control", "no-cache");
  if (con->get_request().get_method() != "GET") {
    con->set_status(websocketpp::http::status_code::method_not_allowed);
    con->set_body("read-only: GET only\n");
    return;
  }
  std::string path = con->get_resource();
  path = path.substr(0, path.find('?'));
  if (path == "/stats") {
    std::lock_guard lock(mutex);
    con->set_status(websocketpp::http::status_code::ok);
    con->append_header("Content-Type", "application/json");
    con->set_body(dump({{"clients", stats.clients},
                        {"frames_sent", stats.frames_sent},
                        {"frames_dropped", stats.frames_dropped},
                        {"clients_closed_bad_input", stats.clients_closed_bad_input}}));
    return;
  }
  const std::string name = path == "/" ? "index.html" : path.substr(1);
  std::ifstream in(options.web_root / name, std::ios::binary);
  if (!safe_file_name(name) || !in) {
    con->set_status(websocketpp::http::status_code::not_found);
    con->set_body("not found\n");
    return;
  }
  std::ostringstream body;
  body << in.rdbuf();
  con->set_status(websocketpp::http::status_code::ok);
  con->append_header("Content-Type", content_type(name));
  con->set_body(body.str());
}

void TopsideServer::Impl::flush_all() {
  flush_pending = false;
  std::lock_guard lock(mutex);
  for (auto& [hdl, c] : clients) {
    while (c->queue.has_frames() && c->con->get_buffered_amount() < options.max_buffered_bytes) {
      const OutgoingFrame f = c->queue.pop();
      const websocketpp::lib::error_code ec = c->con->send(
          f.payload->data(), f.payload->size(),
          f.binary ? websocketpp::frame::opcode::binary : websocketpp::frame::opcode::text);
      if (ec) break;
      ++stats.frames_sent;
    }
  }
}

void TopsideServer::Impl::arm_timer() {
  ws.set_timer(kFlushPeriodMs, [this](const websocketpp::lib::error_code& ec) {
    if (ec || ws.stopped()) return;
    flush_all();
    arm_timer();
  });
}

void TopsideServer::Impl::wake() {
  if (started && !flush_pending.exchange(true)) {
    asio::post(ws.get_io_service(), [this] { flush_all(); });
  }
}

TopsideServer::TopsideServer(ServerOptions options)
    : impl_(std::make_unique<Impl>(std::move(options))) {}

TopsideServer::~TopsideServer() { stop(); }

void TopsideServer::start() {
  Impl& m = *impl_;
  m.setup();
  websocketpp::lib::error_code ec;
  const asio::ip::address address = asio::ip::make_address(m.options.address, ec);
  if (ec) throw std::runtime_error("topside: bad listen address '" + m.options.address + "'");
  m.ws.listen(asio::ip::tcp::endpoint(address, m.options.port), ec);
  if (ec) {
    throw std::runtime_error("topside: cannot listen on " + m.options.address + ":" +
                             std::to_string(m.options.port) + ": " + ec.message());
  }
  m.ws.start_accept();
  m.arm_timer();
  m.started = true;
  m.io_thread = std::thread([&m] { m.ws.run(); });
}

void TopsideServer::stop() {
  Impl& m = *impl_;
  if (!m.started) return;
  m.started = false;
  asio::post(m.ws.get_io_service(), [&m] {
    websocketpp::lib::error_code ec;
    m.ws.stop_listening(ec);
    std::lock_guard lock(m.mutex);
    for (auto& [hdl, c] : m.clients) c->con->close(close_code::going_away, "server stops", ec);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // lets the close frames go out
  m.ws.stop();
  if (m.io_thread.joinable()) m.io_thread.join();
}

std::uint16_t TopsideServer::port() const {
  websocketpp::lib::error_code ec;
  const auto endpoint = impl_->ws.get_local_endpoint(ec);
  return ec ? 0 : endpoint.port();
}

void TopsideServer::publish_view(const std::string& channel, const nlohmann::json& msg,
                                 const std::string& retain_key) {
  auto text = std::make_shared<const std::string>(dump({{"channel", channel}, {"msg", msg}}));
  {
    std::lock_guard lock(impl_->mutex);
    if (!retain_key.empty() && (impl_->retained.size() < kMaxRetained ||
                                impl_->retained.count(retain_key) > 0)) {
      impl_->retained[retain_key] = {++impl_->retained_seq, text};
    }
    for (auto& [hdl, c] : impl_->clients) {
      if (c->foxglove) continue;
      if (c->queue.full()) ++impl_->stats.frames_dropped;
      c->queue.push({text, false});
    }
  }
  impl_->wake();
}

void TopsideServer::publish_foxglove(std::uint32_t channel_id, std::uint64_t log_time_ns,
                                     const nlohmann::json& msg) {
  const std::string payload = dump(msg);
  {
    std::lock_guard lock(impl_->mutex);
    for (auto& [hdl, c] : impl_->clients) {
      const auto [begin, end] = c->subscription_by_channel.equal_range(channel_id);
      for (auto it = begin; it != end; ++it) {
        if (c->queue.full()) ++impl_->stats.frames_dropped;
        c->queue.push({std::make_shared<const std::string>(
                           message_data_frame(it->second, log_time_ns, payload)),
                       true});
      }
    }
  }
  impl_->wake();
}

ServerStats TopsideServer::stats() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

}  // namespace nav::daemon::topside
