// LCM subscriber thread: decode, convert (lcm_json.h, foxglove.h), publish (server.h).
#include "nav/daemon/topside/lcm_bridge.h"

#include <array>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace nav::daemon::topside {
namespace {

std::uint64_t receive_ns(const lcm::ReceiveBuffer* rbuf) {
  return static_cast<std::uint64_t>(rbuf->recv_utime) * 1000u;
}

}  // namespace

struct LcmBridge::Impl {
  Impl(const std::string& url, BridgeChannels ch, TopsideServer& s)
      : lcm(url), channels(std::move(ch)), server(s) {
    if (!lcm.good()) throw std::runtime_error("topside: cannot open LCM at '" + url + "'");
  }

  lcm::LCM lcm;
  BridgeChannels channels;
  TopsideServer& server;
  std::thread thread;
  std::atomic<bool> running{false};
  std::atomic<std::uint64_t> messages{0};
  std::atomic<std::uint64_t> decode_errors{0};
  std::map<std::int64_t, std::array<double, 3>> state_positions;  // for link lines

  template <typename Msg>
  bool decode(const lcm::ReceiveBuffer* rbuf, Msg* msg) {
    ++messages;
    if (msg->decode(rbuf->data, 0, rbuf->data_size) != static_cast<int>(rbuf->data_size)) {
      ++decode_errors;
      return false;
    }
    return true;
  }

  void on_solution(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    navlcm::nav_solution_t m;
    if (!decode(rbuf, &m)) return;
    server.publish_view("NAVD_SOLUTION", to_json(m), "NAVD_SOLUTION");
    server.publish_foxglove(foxglove_channel_id("/navd/pose"), receive_ns(rbuf), pose_in_frame(m));
    server.publish_foxglove(foxglove_channel_id("NAVD_SOLUTION"), receive_ns(rbuf), to_json(m));
  }

  void on_health(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    navlcm::health_t m;
    if (!decode(rbuf, &m)) return;
    server.publish_view("NAVD_HEALTH", to_json(m), "NAVD_HEALTH");
    server.publish_foxglove(foxglove_channel_id("/navd/log"), receive_ns(rbuf), health_log(m));
    server.publish_foxglove(foxglove_channel_id("NAVD_HEALTH"), receive_ns(rbuf), to_json(m));
  }

  void publish_bounds(const std::vector<navlcm::delayed_state_bound_t>& states, std::uint64_t t) {
    for (const auto& s : states) {
      state_positions[s.state_id] = {s.mean_pose[0], s.mean_pose[1], s.mean_pose[2]};
      // One retained frame per state: a late page gets every state's latest bound.
      server.publish_view("NAVD_BOUNDS", to_json(s), "bound/" + std::to_string(s.state_id));
    }
    server.publish_foxglove(foxglove_channel_id("/navd/bounds"), t, bounds_scene_update(states));
  }

  void on_bound(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    navlcm::delayed_state_bound_t m;
    if (decode(rbuf, &m)) publish_bounds({m}, receive_ns(rbuf));
  }

  void on_snapshot(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    navlcm::bounds_snapshot_t m;
    if (decode(rbuf, &m)) publish_bounds(m.states, receive_ns(rbuf));
  }

  void on_link(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    navlcm::camera_link_t m;
    if (!decode(rbuf, &m)) return;
    const std::string key =
        "link/" + std::to_string(m.state_id_i) + "-" + std::to_string(m.state_id_j);
    server.publish_view("NAVD_CAMERA_LINKS", to_json(m), key);
    // Temporal: no known delayed state lies between the two (consecutive images).
    const std::int64_t lo = std::min(m.state_id_i, m.state_id_j);
    const std::int64_t hi = std::max(m.state_id_i, m.state_id_j);
    const auto next = state_positions.upper_bound(lo);
    const bool temporal = next == state_positions.end() || next->first >= hi;
    server.publish_foxglove(foxglove_channel_id("/navd/links"), receive_ns(rbuf),
                            link_scene_update(m, state_positions, temporal));
    server.publish_foxglove(foxglove_channel_id("NAVD_CAMERA_LINKS"), receive_ns(rbuf), to_json(m));
  }

  void on_proposal(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    navlcm::link_proposal_t m;
    if (!decode(rbuf, &m)) return;
    server.publish_view("NAV_LINK_PROPOSAL", to_json(m), "proposal/" + std::to_string(m.sequence));
    server.publish_foxglove(foxglove_channel_id("NAV_LINK_PROPOSAL"), receive_ns(rbuf), to_json(m));
  }
};

LcmBridge::LcmBridge(const std::string& lcm_url, BridgeChannels channels, TopsideServer& server)
    : impl_(std::make_unique<Impl>(lcm_url, std::move(channels), server)) {
  Impl& m = *impl_;
  const auto re = [](const std::string& name) { return "^" + name + "$"; };
  m.lcm.subscribe(re(m.channels.nav_solution), &Impl::on_solution, &m);
  m.lcm.subscribe(re(m.channels.health), &Impl::on_health, &m);
  m.lcm.subscribe(re(m.channels.bounds), &Impl::on_bound, &m);
  m.lcm.subscribe(re(m.channels.bounds_snapshot), &Impl::on_snapshot, &m);
  m.lcm.subscribe(re(m.channels.camera_links), &Impl::on_link, &m);
  m.lcm.subscribe(re(m.channels.link_proposals), &Impl::on_proposal, &m);
}

LcmBridge::~LcmBridge() { stop(); }

void LcmBridge::start() {
  Impl& m = *impl_;
  m.running = true;
  m.thread = std::thread([&m] {
    while (m.running) m.lcm.handleTimeout(100);
  });
}

void LcmBridge::stop() {
  impl_->running = false;
  if (impl_->thread.joinable()) impl_->thread.join();
}

BridgeStats LcmBridge::stats() const { return {impl_->messages.load(), impl_->decode_errors.load()}; }

}  // namespace nav::daemon::topside
