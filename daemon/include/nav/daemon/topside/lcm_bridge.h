#pragma once
// LcmBridge: the LCM subscriber thread of navtool topside. It decodes navd's channels, turns
// each message into the page's JSON (lcm_json.h) and the Foxglove schemas (foxglove.h), and
// publishes both through a TopsideServer. It only subscribes: it never publishes on LCM.
// A message that does not decode as its channel's type is counted and skipped. The page's feed
// names channels by navd's default names (NAVD_SOLUTION, NAVD_HEALTH, NAVD_BOUNDS for bounds
// and snapshot states alike, NAVD_CAMERA_LINKS, NAV_LINK_PROPOSAL) whatever they are called on LCM.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "nav/daemon/topside/server.h"

namespace nav::daemon::topside {

/// navd's channel names (config.h LcmChannels defaults; rename with the same keys as navd).
struct BridgeChannels {
  std::string nav_solution = "NAVD_SOLUTION";
  std::string health = "NAVD_HEALTH";
  std::string bounds = "NAVD_BOUNDS";
  std::string bounds_snapshot = "NAVD_BOUNDS_SNAPSHOT";
  std::string camera_links = "NAVD_CAMERA_LINKS";
  std::string link_proposals = "NAV_LINK_PROPOSAL";
};

struct BridgeStats {
  std::uint64_t messages = 0;
  std::uint64_t decode_errors = 0;
};

class LcmBridge {
 public:
  /// Opens LCM at `lcm_url`; throws std::runtime_error if it cannot.
  LcmBridge(const std::string& lcm_url, BridgeChannels channels, TopsideServer& server);
  ~LcmBridge();
  LcmBridge(const LcmBridge&) = delete;
  LcmBridge& operator=(const LcmBridge&) = delete;

  void start();  ///< starts the subscriber thread
  void stop();   ///< joins it (idempotent)
  BridgeStats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace nav::daemon::topside
