#pragma once
// Live mode's link to an asynchronous vision stage (docs/architecture.md):
// * RegistrationListener: a thread with its own LCM instance (lcm.url) subscribed to
//   lcm.channels.registration (default NAV_REGISTRATION); every registration_t it decodes goes
//   into the RegistrationInbox (bounded SPSC queue, drops counted) that the filter thread
//   drains into the RegistrationTable the NavFilter reads. A vision process, or until it
//   exists an oracle stand-in in the HIL tests, answers there. With lcm.registration_signing
//   the listener checks each answer's signature first (registration_signature.h): unsigned,
//   bad and stale ones are counted and never queued.
// * LinkProposalPublisher: on the filter thread after each measurement, link_proposal_t for
//   every pair the NavFilter newly keeps waiting for its registration
//   (lcm.channels.link_proposals, default NAV_LINK_PROPOSAL): what a vision process needs to
//   register the two images and answer, with the pair's pose prior and the images' altitudes
//   (has_prior false when the camera pair cannot be predicted: daemon/vision/camera_prior.h)
//   and this run's id (proposal_ledger.h), recorded in the inbox's ProposalLedger so that only
//   answers to these proposals change the map.

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "nav/core/navigation/nav_filter.h"
#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/filter_options.h"
#include "nav/daemon/filter/registration_signature.h"
#include "nav/daemon/queue/registration_inbox.h"

namespace navlcm {
class health_t;
}  // namespace navlcm
namespace lcm {
class LCM;
class ReceiveBuffer;
}  // namespace lcm

namespace nav::daemon::service {

class RegistrationListener {
 public:
  /// Subscribes at once (so nothing published after the constructor is missed); good() false
  /// when LCM cannot open lcm.url or cannot receive on it (then nothing is received and no
  /// thread runs). With `key` every answer must be signed with it (window:
  /// config.registration_signing.window_s).
  RegistrationListener(const daemon::LcmConfig& config, daemon::RegistrationInbox& inbox,
                       std::optional<daemon::SigningKey> key = std::nullopt);
  ~RegistrationListener();  ///< stops and joins the thread
  bool good() const;
  /// Starts the receive thread; it returns within ~50 ms of `stop`.
  void start(const std::atomic<bool>& stop);
  void join();
  std::uint64_t decode_errors() const { return decode_errors_.load(); }
  std::uint64_t unsigned_answers() const { return unsigned_.load(); }
  std::uint64_t bad_signatures() const { return bad_signature_.load(); }
  std::uint64_t stale_signatures() const { return stale_signature_.load(); }

 private:
  static void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                         RegistrationListener* self);
  std::unique_ptr<lcm::LCM> lcm_;
  bool admit_signed(const navlcm::registration_t& answer);
  daemon::RegistrationInbox& inbox_;
  std::optional<daemon::SignatureChecker> signatures_;
  std::thread thread_;
  std::atomic<std::uint64_t> decode_errors_{0};
  std::atomic<std::uint64_t> unsigned_{0}, bad_signature_{0}, stale_signature_{0};
  bool receiving_ = false;  ///< LCM's receive side is set up (a valid getFileno())
};

class LinkProposalPublisher {
 public:
  /// Records every proposal in `ledger` (filter thread, like on_measurement) and publishes it
  /// with ledger.run_id().
  LinkProposalPublisher(const daemon::NavdConfig& config, daemon::ProposalLedger& ledger);
  ~LinkProposalPublisher();
  /// Filter thread: publishes the pending pairs newer than the last call.
  void on_measurement(const daemon::NavFilter& filter);
  std::uint64_t published() const { return published_; }
  std::uint64_t failures() const { return failures_; }

 private:
  std::string channel_;
  daemon::ProposalLedger& ledger_;
  std::string image_dir_prefix_;  ///< "images/" when a camera writes PNGs, else ""
  core::Vec6 x_body_camera_ = core::Vec6::Zero();  ///< the first camera's mount
  daemon::VisionConfig vision_;                    ///< scene-depth sigma of the prior
  std::unique_ptr<lcm::LCM> lcm_;
  std::uint64_t last_sequence_ = 0;
  std::uint64_t published_ = 0, failures_ = 0;
};

/// `,"registrations":N,...` for live mode's JSON line: inbox, listener (signatures) and
/// pending-pair counters.
std::string registration_summary_json(const daemon::RegistrationInbox& inbox,
                                      const RegistrationListener& listener,
                                      const daemon::NavFilter& filter);

/// The registration counters of health_t (received and every rejection reason).
void fill_registration_health(const daemon::RegistrationInbox& inbox,
                              const RegistrationListener& listener, navlcm::health_t& health);

}  // namespace nav::daemon::service
