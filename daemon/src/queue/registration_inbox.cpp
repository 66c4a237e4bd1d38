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

RegistrationInbox::RegistrationInbox(std::size_t capacity) {
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

std::size_t RegistrationInbox::drain() {
  std::size_t taken = 0;
  navlcm::registration_t r;
  while (queue_->q.try_dequeue(r)) {
    ++taken;
    const core::Registration registration = registration_from_message(r);
    if (const std::optional<std::string> problem = core::registration_problem(registration)) {
      invalid_.fetch_add(1, kRelaxed);
      spdlog::warn("navd: registration_t ignored: {}", *problem);
      continue;
    }
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
  return c;
}

}  // namespace nav::daemon
