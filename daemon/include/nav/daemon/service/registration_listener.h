#pragma once
// Live mode's link to an asynchronous vision stage (docs/architecture.md):
// * RegistrationListener: a thread with its own LCM instance (lcm.url) subscribed to
//   lcm.channels.registration (default NAV_REGISTRATION); every registration_t it decodes goes
//   into the RegistrationInbox (bounded SPSC queue, drops counted) that the filter thread
//   drains into the RegistrationTable the NavFilter reads. A vision process, or until it
//   exists hil-play publishing a dive log's oracle registrations, answers there.
// * LinkProposalPublisher: on the filter thread after each measurement, link_proposal_t for
//   every pair the NavFilter newly keeps waiting for its registration
//   (lcm.channels.link_proposals, default NAV_LINK_PROPOSAL): what a vision process needs to
//   register the two images and answer.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "nav/core/navigation/nav_filter.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/queue/registration_inbox.h"

namespace lcm {
class LCM;
class ReceiveBuffer;
}  // namespace lcm

namespace nav::daemon::service {

class RegistrationListener {
 public:
  /// Subscribes at once (so nothing published after the constructor is missed); good() false
  /// when LCM cannot open lcm.url or cannot receive on it (then nothing is received and no
  /// thread runs).
  RegistrationListener(const daemon::LcmConfig& config, daemon::RegistrationInbox& inbox);
  ~RegistrationListener();  ///< stops and joins the thread
  bool good() const;
  /// Starts the receive thread; it returns within ~50 ms of `stop`.
  void start(const std::atomic<bool>& stop);
  void join();
  std::uint64_t decode_errors() const { return decode_errors_.load(); }

 private:
  static void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                         RegistrationListener* self);
  std::unique_ptr<lcm::LCM> lcm_;
  daemon::RegistrationInbox& inbox_;
  std::thread thread_;
  std::atomic<std::uint64_t> decode_errors_{0};
  bool receiving_ = false;  ///< LCM's receive side is set up (a valid getFileno())
};

class LinkProposalPublisher {
 public:
  explicit LinkProposalPublisher(const daemon::NavdConfig& config);
  ~LinkProposalPublisher();
  /// Filter thread: publishes the pending pairs newer than the last call.
  void on_measurement(const daemon::NavFilter& filter);
  std::uint64_t published() const { return published_; }
  std::uint64_t failures() const { return failures_; }

 private:
  std::string channel_;
  std::string image_dir_prefix_;  ///< "images/" when a camera writes PNGs, else ""
  std::unique_ptr<lcm::LCM> lcm_;
  std::uint64_t last_sequence_ = 0;
  std::uint64_t published_ = 0, failures_ = 0;
};

/// `,"registrations":N,...` for live mode's JSON line: inbox and pending-pair counters.
std::string registration_summary_json(const daemon::RegistrationInbox& inbox,
                                      const daemon::NavFilter& filter);

}  // namespace nav::daemon::service
