// Bounded SPSC hand-over of registrations to the filter thread: see registration_inbox.h.
#include "nav/daemon/queue/registration_inbox.h"

#include <readerwriterqueue.h>
#include <spdlog/spdlog.h>

#include <optional>
#include <stdexcept>
#include <string>

namespace nav::daemon {
namespace {
constexpr auto kRelaxed = std::memory_order_relaxed;
}  // namespace

struct RegistrationInbox::Queue {
  explicit Queue(std::size_t capacity) : q(capacity) {}
  moodycamel::ReaderWriterQueue<navlcm::registration_t> q;
};

RegistrationInbox::RegistrationInbox(std::size_t capacity, std::int64_t run_id)
    : ledger_(run_id) {
  if (capacity < 1) throw std::invalid_argument("RegistrationInbox: capacity must be >= 1");
  queue_ = std::make_unique<Queue>(capacity);
}

RegistrationInbox::~RegistrationInbox() = default;

bool RegistrationInbox::offer(const navlcm::registration_t& registration) {
  if (!queue_->q.try_enqueue(registration)) {  // never allocates: full means dropped
    dropped_.fetch_add(1, kRelaxed);
    return false;
  }
  received_.fetch_add(1, kRelaxed);
  return true;
}

void RegistrationInbox::reject(Provenance provenance, const navlcm::registration_t& r) {
  std::atomic<std::uint64_t>* counter = nullptr;
  switch (provenance) {
    case Provenance::kWrongRun: counter = &wrong_run_; break;
    case Provenance::kUnknownSequence: counter = &unknown_sequence_; break;
    case Provenance::kAlreadyAnswered: counter = &already_answered_; break;
    case Provenance::kExpired: counter = &expired_; break;
    case Provenance::kPairMismatch: counter = &pair_mismatch_; break;
    case Provenance::kOurs: return;
  }
  // The first of each reason is logged; the rest are counted (health_t), so a replayed log
  // cannot flood the journal.
  if (counter->fetch_add(1, kRelaxed) == 0) {
    spdlog::warn(
        "navd: registration_t {}-{} (run {:x}, sequence {}) rejected: {} (further ones counted "
        "in health_t)",
        r.frame_id_i, r.frame_id_j, static_cast<std::uint64_t>(r.run_id), r.sequence,
        to_string(provenance));
  }
}

bool RegistrationInbox::has_queued() const { return queue_->q.peek() != nullptr; }

std::size_t RegistrationInbox::drain(std::span<const core::PendingRegistration> waiting) {
  std::size_t taken = 0;
  navlcm::registration_t r;
  while (queue_->q.try_dequeue(r)) {
    ++taken;
    if (const Provenance p = ledger_.check(r, waiting); p != Provenance::kOurs) {
      reject(p, r);
      continue;
    }
    const core::Registration registration = registration_from_message(r);
    if (const std::optional<std::string> problem = core::registration_problem(registration)) {
      invalid_.fetch_add(1, kRelaxed);
      spdlog::warn("navd: registration_t ignored: {}", *problem);
      continue;
    }
    ledger_.answered(static_cast<std::uint64_t>(r.sequence));
    if (table_.insert(registration)) {
      inserted_.fetch_add(1, kRelaxed);
    } else {
      duplicates_.fetch_add(1, kRelaxed);
    }
  }
  return taken;
}

RegistrationInboxCounters RegistrationInbox::counters() const {
  RegistrationInboxCounters c;
  c.received = received_.load(kRelaxed);
  c.dropped = dropped_.load(kRelaxed);
  c.inserted = inserted_.load(kRelaxed);
  c.duplicates = duplicates_.load(kRelaxed);
  c.invalid = invalid_.load(kRelaxed);
  c.wrong_run = wrong_run_.load(kRelaxed);
  c.unknown_sequence = unknown_sequence_.load(kRelaxed);
  c.already_answered = already_answered_.load(kRelaxed);
  c.expired = expired_.load(kRelaxed);
  c.pair_mismatch = pair_mismatch_.load(kRelaxed);
  return c;
}

}  // namespace nav::daemon
