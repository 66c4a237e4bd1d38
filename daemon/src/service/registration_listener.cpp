#include "nav/daemon/service/registration_listener.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/health_t.hpp>
#include <navlcm/link_proposal_t.hpp>
#include <navlcm/registration_t.hpp>

#include "nav/daemon/system/host_clock.h"
#include "nav/daemon/sources/camera_source.h"
#include "nav/daemon/vision/camera_prior.h"

namespace nav::daemon::service {
RegistrationListener::RegistrationListener(const daemon::LcmConfig& config,
                                           daemon::RegistrationInbox& inbox,
                                           std::optional<daemon::SigningKey> key)
    : lcm_(std::make_unique<lcm::LCM>(config.url)), inbox_(inbox) {
  if (key) {
    signatures_.emplace(std::move(*key),
                        static_cast<std::int64_t>(config.registration_signing.window_s * 1e6));
  }
  if (!lcm_->good()) return;
  // getFileno() sets up LCM's receive side now (udpm: socket, receive thread and a multicast
  // self test that waits up to 10 s) and is -1 when that fails. LCM 1.3.1's handleTimeout()
  // would put that -1 into an fd_set, which glibc aborts on (found in hil-tests/vm, where the
  // self test failed): so without a descriptor the receive thread never starts.
  receiving_ = lcm_->getFileno() >= 0;
  if (!receiving_) {
    spdlog::error(
        "navd: LCM cannot receive on {} (its multicast self test failed: check the route to "
        "224.0.0.0/4 and IPAddressAllow=); {} answers are not received",
        config.url, config.registration.name);
    return;
  }
  lcm_->subscribeFunction(config.registration.name, &RegistrationListener::on_message, this);
}

void RegistrationListener::on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                                      RegistrationListener* self) {
  navlcm::registration_t r;
  if (r.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) {
    self->decode_errors_.fetch_add(1);
    spdlog::warn("navd: {}: {} bytes that are not a registration_t", channel, rbuf->data_size);
    return;
  }
  if (self->signatures_ && !self->admit_signed(r)) return;
  self->inbox_.offer(r);  // a full inbox counts the drop
}

bool RegistrationListener::admit_signed(const navlcm::registration_t& r) {
  const daemon::SignatureVerdict v = signatures_->check(r, daemon::realtime_us());
  std::atomic<std::uint64_t>* counter = v == daemon::SignatureVerdict::kUnsigned ? &unsigned_
                                        : v == daemon::SignatureVerdict::kBadSignature
                                            ? &bad_signature_
                                            : &stale_signature_;
  if (v == daemon::SignatureVerdict::kValid) return true;
  if (counter->fetch_add(1) == 0) {  // the first of each reason logged, all counted
    spdlog::warn("navd: registration_t {}-{} (signer {}) rejected: {} (further ones counted in "
                 "health_t)",
                 r.frame_id_i, r.frame_id_j, r.signer_id, daemon::to_string(v));
  }
  return false;
}

RegistrationListener::~RegistrationListener() { join(); }

bool RegistrationListener::good() const { return lcm_->good() && receiving_; }

void RegistrationListener::start(const std::atomic<bool>& stop) {
  if (!good()) return;
  thread_ = std::thread([this, &stop] {
    while (!stop.load()) lcm_->handleTimeout(50);
  });
}

void RegistrationListener::join() {
  if (thread_.joinable()) thread_.join();
}

LinkProposalPublisher::LinkProposalPublisher(const daemon::NavdConfig& config,
                                             daemon::ProposalLedger& ledger)
    : channel_(config.lcm.link_proposals.name),
      ledger_(ledger),
      vision_(config.vision),
      lcm_(std::make_unique<lcm::LCM>(config.lcm.url)) {
  for (const daemon::SensorConfig& s : config.sensors) {
    if (!s.camera.image_dir.empty()) image_dir_prefix_ = "images/";
  }
  for (auto it = config.sensors.rbegin(); it != config.sensors.rend(); ++it) {
    if (!daemon::is_camera(it->type)) continue;  // the first camera wins (filter_options.cpp)
    const auto& m = it->mount;
    x_body_camera_ << m.lever_arm_m[0], m.lever_arm_m[1], m.lever_arm_m[2], m.rpy_rad[0],
        m.rpy_rad[1], m.rpy_rad[2];
  }
}

namespace {

/// The pair's pose prior and altitudes (link_proposal_t's prior fields).
void fill_prior(const daemon::NavFilter& filter, const daemon::PendingRegistration& p,
                const core::Vec6& x_body_camera, const daemon::VisionConfig& vision,
                navlcm::link_proposal_t& msg) {
  const auto prior = daemon::vision::pair_prior_from_filter(filter, p, x_body_camera, vision,
                                                            nullptr);
  msg.has_prior = prior.has_value();
  if (!prior) return;
  for (int r = 0; r < 6; ++r) {
    msg.prior_x_i_j[r] = prior->x_i_j[r];
    for (int c = 0; c < 6; ++c) msg.prior_covariance[6 * r + c] = prior->covariance(r, c);
  }
  // The images' own altitudes (the answerer forms its scene-depth interval from both:
  // nav/vision/pccs.h scene_depth_prior) and the sigma of image i's.
  if (const core::ImageRecord* image_i = daemon::vision::find_image(filter, p.frame_i))
    msg.altitude_i_m = image_i->altitude_m;
  msg.altitude_j_m = filter.images().back().altitude_m;  // the robot is image j (prior found)
  msg.altitude_sigma_m =
      vision.depth_sigma_fraction * msg.altitude_i_m + vision.depth_sigma_floor_m;
}

}  // namespace

LinkProposalPublisher::~LinkProposalPublisher() = default;

void LinkProposalPublisher::on_measurement(const daemon::NavFilter& filter) {
  if (filter.last_pending_sequence() == last_sequence_) return;
  for (const daemon::PendingRegistration& p : filter.pending_registrations()) {
    if (p.sequence <= last_sequence_) continue;
    navlcm::link_proposal_t msg{};
    msg.utime = daemon::realtime_us();
    msg.sequence = static_cast<std::int64_t>(p.sequence);
    msg.frame_id_i = static_cast<std::int64_t>(p.frame_i);
    msg.frame_id_j = static_cast<std::int64_t>(p.frame_j);
    msg.time_of_validity_i_us = p.t_i_us;
    msg.time_of_validity_j_us = p.t_j_us;
    msg.deadline_utime = p.deadline_realtime_us;
    msg.run_id = ledger_.run_id();
    ledger_.propose(p.sequence);
    if (!image_dir_prefix_.empty()) {
      msg.image_file_i = image_dir_prefix_ + daemon::frame_png_name(p.frame_i);
      msg.image_file_j = image_dir_prefix_ + daemon::frame_png_name(p.frame_j);
    }
    fill_prior(filter, p, x_body_camera_, vision_, msg);
    if (lcm_->good() && lcm_->publish(channel_, &msg) == 0) {
      ++published_;
    } else {
      ++failures_;
    }
  }
  last_sequence_ = filter.last_pending_sequence();
}

std::string registration_summary_json(const daemon::RegistrationInbox& inbox,
                                      const RegistrationListener& listener,
                                      const daemon::NavFilter& filter) {
  const daemon::RegistrationInboxCounters c = inbox.counters();
  const daemon::PendingRegistrationCounters& p = filter.pending_counters();
  char text[1024];
  std::snprintf(
      text, sizeof text,
      ",\"links_accepted\":%llu,\"registrations\":%llu,\"registrations_dropped\":%llu,"
      "\"registrations_duplicate\":%llu,\"registrations_invalid\":%llu,"
      "\"pairs_deferred\":%llu,\"pairs_answered\":%llu,\"pairs_expired\":%llu,"
      "\"pairs_not_deferred_full\":%llu,\"registrations_wrong_run\":%llu,"
      "\"registrations_unknown_sequence\":%llu,\"registrations_already_answered\":%llu,"
      "\"registrations_expired\":%llu,\"registrations_pair_mismatch\":%llu,"
      "\"registrations_inserted\":%llu",
      static_cast<unsigned long long>(filter.counters().links_accepted),
      static_cast<unsigned long long>(c.received), static_cast<unsigned long long>(c.dropped),
      static_cast<unsigned long long>(c.duplicates), static_cast<unsigned long long>(c.invalid),
      static_cast<unsigned long long>(p.deferred), static_cast<unsigned long long>(p.applied),
      static_cast<unsigned long long>(p.expired), static_cast<unsigned long long>(p.dropped_full),
      static_cast<unsigned long long>(c.wrong_run),
      static_cast<unsigned long long>(c.unknown_sequence),
      static_cast<unsigned long long>(c.already_answered),
      static_cast<unsigned long long>(c.expired), static_cast<unsigned long long>(c.pair_mismatch),
      static_cast<unsigned long long>(c.inserted));
  char signing[256];
  std::snprintf(signing, sizeof signing,
                ",\"registrations_unsigned\":%llu,\"registrations_bad_signature\":%llu,"
                "\"registrations_stale_signature\":%llu",
                static_cast<unsigned long long>(listener.unsigned_answers()),
                static_cast<unsigned long long>(listener.bad_signatures()),
                static_cast<unsigned long long>(listener.stale_signatures()));
  return std::string(text) + signing;
}

void fill_registration_health(const daemon::RegistrationInbox& inbox,
                              const RegistrationListener& listener, navlcm::health_t& health) {
  const daemon::RegistrationInboxCounters c = inbox.counters();
  auto i64 = [](std::uint64_t v) { return static_cast<std::int64_t>(v); };
  health.registrations_received =
      i64(c.received + c.dropped + listener.unsigned_answers() + listener.bad_signatures() +
          listener.stale_signatures());
  health.registrations_wrong_run = i64(c.wrong_run);
  health.registrations_unknown_sequence = i64(c.unknown_sequence);
  health.registrations_expired = i64(c.expired);
  health.registrations_already_answered = i64(c.already_answered);
  health.registrations_pair_mismatch = i64(c.pair_mismatch);
  health.registrations_invalid = i64(c.invalid);
  health.registrations_unsigned = i64(listener.unsigned_answers());
  health.registrations_bad_signature = i64(listener.bad_signatures());
  health.registrations_stale_signature = i64(listener.stale_signatures());
}

}  // namespace nav::daemon::service
