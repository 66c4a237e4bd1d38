// Proposed pairs waiting for an asynchronous registration (navigation/pending_registrations.h).
#include "nav/core/navigation/pending_registrations.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nav::core {

PendingRegistrations::PendingRegistrations(double wait_s, int max_pending)
    : enabled_(wait_s > 0.0),
      wait_us_(static_cast<std::int64_t>(std::llround(wait_s * 1e6))),
      max_pending_(static_cast<std::size_t>(std::max(max_pending, 1))) {
  if (!(wait_s >= 0.0 && wait_s <= 3600.0) || max_pending < 1 || max_pending > 100000) {
    throw std::invalid_argument(
        "NavFilterOptions: registration_wait_s must be in [0, 3600] s (is " +
        std::to_string(wait_s) + "), max_pending_registrations in [1, 100000] (is " +
        std::to_string(max_pending) + ")");
  }
  if (wait_s > 0.0) pending_.reserve(max_pending_);
}

std::optional<RegistrationResult> PendingRegistrations::lookup(const RegistrationTable* table,
                                                               const PendingRegistration& p) {
  if (table == nullptr) return std::nullopt;
  return table->find(static_cast<std::int64_t>(p.frame_i), static_cast<std::int64_t>(p.frame_j));
}

bool PendingRegistrations::defer(const RegistrationTable* table, Entry entry,
                                 std::int64_t now_realtime_us) {
  if (!enabled()) return false;
  const std::optional<RegistrationResult> reg = lookup(table, entry.info);
  if (reg && reg->available_us <= now_realtime_us) return false;  // answered already
  if (pending_.size() >= max_pending_) {
    ++counters_.dropped_full;  // looked up now: not registered
    return false;
  }
  entry.info.sequence = ++sequence_;
  entry.info.asked_realtime_us = now_realtime_us;
  entry.info.deadline_realtime_us = now_realtime_us + wait_us_;
  const std::int64_t deadline_us = entry.info.deadline_realtime_us;
  pending_.push_back(std::move(entry));
  ++counters_.deferred;
  next_check_us_ = std::min(next_check_us_, deadline_us);
  if (reg) next_check_us_ = std::min(next_check_us_, reg->available_us);
  return true;
}

std::vector<PendingRegistration> PendingRegistrations::list() const {
  std::vector<PendingRegistration> out;
  out.reserve(pending_.size());
  for (const Entry& e : pending_) out.push_back(e.info);
  return out;
}

}  // namespace nav::core
