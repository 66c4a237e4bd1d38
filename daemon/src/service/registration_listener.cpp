#include "nav/daemon/service/registration_listener.h"

#include <spdlog/spdlog.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <navlcm/link_proposal_t.hpp>
#include <navlcm/registration_t.hpp>

#include "nav/daemon/system/host_clock.h"
#include "nav/daemon/sources/camera_source.h"

namespace nav::daemon::service {
RegistrationListener::RegistrationListener(const daemon::LcmConfig& config,
                                           daemon::RegistrationInbox& inbox)
    : lcm_(std::make_unique<lcm::LCM>(config.url)), inbox_(inbox) {
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
  self->inbox_.offer(r);  // a full inbox counts the drop
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

LinkProposalPublisher::LinkProposalPublisher(const daemon::NavdConfig& config)
    : channel_(config.lcm.link_proposals.name), lcm_(std::make_unique<lcm::LCM>(config.lcm.url)) {
  for (const daemon::SensorConfig& s : config.sensors) {
    if (!s.camera.image_dir.empty()) image_dir_prefix_ = "images/";
  }
}

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
    if (!image_dir_prefix_.empty()) {
      msg.image_file_i = image_dir_prefix_ + daemon::frame_png_name(p.frame_i);
      msg.image_file_j = image_dir_prefix_ + daemon::frame_png_name(p.frame_j);
    }
    if (lcm_->good() && lcm_->publish(channel_, &msg) == 0) {
      ++published_;
    } else {
      ++failures_;
    }
  }
  last_sequence_ = filter.last_pending_sequence();
}

std::string registration_summary_json(const daemon::RegistrationInbox& inbox,
                                      const daemon::NavFilter& filter) {
  const daemon::RegistrationInboxCounters c = inbox.counters();
  const daemon::PendingRegistrationCounters& p = filter.pending_counters();
  char text[512];
  std::snprintf(
      text, sizeof text,
      ",\"links_accepted\":%llu,\"registrations\":%llu,\"registrations_dropped\":%llu,"
      "\"registrations_duplicate\":%llu,\"registrations_invalid\":%llu,"
      "\"pairs_deferred\":%llu,\"pairs_answered\":%llu,\"pairs_expired\":%llu,"
      "\"pairs_not_deferred_full\":%llu",
      static_cast<unsigned long long>(filter.counters().links_accepted),
      static_cast<unsigned long long>(c.received), static_cast<unsigned long long>(c.dropped),
      static_cast<unsigned long long>(c.duplicates), static_cast<unsigned long long>(c.invalid),
      static_cast<unsigned long long>(p.deferred), static_cast<unsigned long long>(p.applied),
      static_cast<unsigned long long>(p.expired), static_cast<unsigned long long>(p.dropped_full));
  return text;
}

}  // namespace nav::daemon::service
