#pragma once
// Live mode's own vision stage (config vision.enabled; docs/architecture.md "Vision in the
// loop"): a VisionLink (daemon/vision/vision_link.h) fed by the filter thread, whose answers
// this publisher sends as registration_t on lcm.channels.registration (NAV_REGISTRATION), the
// channel an external vision process would use. navd's RegistrationListener takes them from
// there into the filter like any other answer, so they are also in the dive log and visible
// topside. Each answer echoes this run's id and the proposal's sequence (proposal_ledger.h) and,
// when registrations are signed, is signed as signer kSignerId (registration_signature.h).
// publish() is called on the worker threads (serialised here).

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include "nav/daemon/config/config.h"
#include "nav/daemon/filter/registration_signature.h"
#include "nav/daemon/vision/vision_link.h"

namespace lcm {
class LCM;
}

namespace nav::daemon::service {

class VisionAnswerPublisher {
 public:
  /// signer_id of navd's own answers when registrations are signed.
  static constexpr std::int32_t kSignerId = 1;

  VisionAnswerPublisher(const daemon::LcmConfig& config, std::int64_t run_id);
  ~VisionAnswerPublisher();
  /// Signs every later answer with `key` (call before the worker starts answering).
  void set_signing_key(daemon::SigningKey key) { key_ = std::move(key); }
  /// registration_t of the answer, utime = now (when the result became available).
  void publish(const daemon::vision::VisionAnswer& answer);
  std::uint64_t published() const { return published_.load(); }
  std::uint64_t failures() const { return failures_.load(); }

 private:
  std::string channel_;
  std::int64_t run_id_;
  daemon::SigningKey key_;            ///< empty: unsigned
  std::int64_t last_signed_us_ = 0;   ///< signing times strictly increase
  std::mutex mutex_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::atomic<std::uint64_t> published_{0}, failures_{0};
};

/// The live VisionLink of `config` (frames in vision.image_dir, else the camera's image_dir)
/// answering through `answers`; null unless vision.enabled. Throws std::invalid_argument when
/// no frame directory is known or the camera is unusable.
std::unique_ptr<daemon::vision::VisionLink> make_live_vision(const daemon::NavdConfig& config,
                                                            VisionAnswerPublisher& answers);

}  // namespace nav::daemon::service
