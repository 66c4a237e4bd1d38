#pragma once
// Proposed pairs waiting for an asynchronous registration: the vision stage answers a pair
// later than its image. Algorithm (NavFilterOptions::registration_wait_s > 0):
// * At the image, a proposed pair whose registration is not in the table with available_us
//   (its host CLOCK_REALTIME) <= the current measurement's host_realtime_us is deferred, with
//   its proposal joint (at most max_pending pairs; beyond, it is looked up now and counted
//   dropped_full).
// * Before every later measurement (after its prediction) each pending pair whose registration
//   is available at that measurement's host_realtime_us is resolved with it (NavFilter gates it
//   with the stored joint, an upper bound of the current joint since information only grows,
//   and applies it between the two delayed states); one not answered within the wait of its
//   image's receive time expires (not registered).
// Because availability is judged by the registrations' utime against the measurements' receive
// times, a table filled before a replay and one filled while it runs give the same links when
// every registration is inserted before the first measurement received at or after its utime.
// Pending pairs are not checkpointed (a resumed filter forgets them). Owner thread only; the
// storage is reserved at construction.

#include <cstdint>
#include <cstddef>
#include <limits>
#include <optional>
#include <vector>

#include "nav/core/navigation/registration_table.h"
#include "nav/core/recovery/bounds.h"

namespace nav::core {

/// A proposed pair waiting for its registration.
struct PendingRegistration {
  std::uint64_t sequence = 0;              ///< 1, 2, ... in proposal order
  std::uint64_t frame_i = 0, frame_j = 0;  ///< earlier, later image
  std::int64_t t_i_us = 0, t_j_us = 0;     ///< their times of validity
  std::int64_t asked_realtime_us = 0;      ///< image j's host_realtime_us
  std::int64_t deadline_realtime_us = 0;   ///< asked + registration_wait_s
};

struct PendingRegistrationCounters {
  std::uint64_t deferred = 0;      ///< pairs that waited for their registration
  std::uint64_t applied = 0;       ///< registration arrived in time (gated, maybe accepted)
  std::uint64_t accepted = 0;      ///< of applied: accepted links
  std::uint64_t expired = 0;       ///< no registration within the wait (or at the end)
  std::uint64_t dropped_full = 0;  ///< not deferred: max_pending reached
};

class PendingRegistrations {
 public:
  struct Entry {
    PendingRegistration info;
    LinkProposal joint;        ///< the proposal joint at the image
    std::size_t image_j = 0;   ///< NavFilter's image index of frame_j
    std::size_t proposal = 0;  ///< NavFilter's proposal record of that image
  };

  /// wait_s in [0, 3600] (0: never defer), max_pending in [1, 100000]; throws
  /// std::invalid_argument naming the value otherwise.
  PendingRegistrations(double wait_s, int max_pending);

  bool enabled() const { return enabled_; }
  /// Defers the pair unless its registration is available at now_realtime_us (or the set is
  /// full); true when deferred. `entry.info.sequence`/deadline are filled here.
  bool defer(const RegistrationTable* table, Entry entry, std::int64_t now_realtime_us);
  /// Calls resolve(entry, &registration) for each pair answered by realtime_us and
  /// resolve(entry, nullptr) for each overdue one, in proposal order, and drops them.
  template <class Resolve>
  void resolve_due(const RegistrationTable* table, std::int64_t realtime_us, Resolve&& resolve);
  /// Calls resolve(entry, nullptr) for every pair (end of data) and drops them.
  template <class Resolve>
  void expire_all(Resolve&& resolve);

  std::vector<PendingRegistration> list() const;
  std::uint64_t last_sequence() const { return sequence_; }
  const PendingRegistrationCounters& counters() const { return counters_; }
  PendingRegistrationCounters& counters() { return counters_; }

 private:
  static std::optional<RegistrationResult> lookup(const RegistrationTable* table,
                                                  const PendingRegistration& p);
  bool enabled_;
  std::int64_t wait_us_;
  std::size_t max_pending_;
  std::vector<Entry> pending_;
  std::uint64_t sequence_ = 0;
  std::uint64_t seen_generation_ = 0;  ///< table->generation() at the last scan
  std::int64_t next_check_us_ = 0;     ///< earliest availability / deadline pending
  PendingRegistrationCounters counters_;
};

template <class Resolve>
void PendingRegistrations::resolve_due(const RegistrationTable* table, std::int64_t realtime_us,
                                       Resolve&& resolve) {
  if (pending_.empty()) return;
  const std::uint64_t generation = table ? table->generation() : 0;
  if (generation == seen_generation_ && realtime_us < next_check_us_) return;
  seen_generation_ = generation;
  next_check_us_ = std::numeric_limits<std::int64_t>::max();
  auto keep = pending_.begin();
  for (auto it = pending_.begin(); it != pending_.end(); ++it) {
    const std::optional<RegistrationResult> reg = lookup(table, it->info);
    if (reg && reg->available_us <= realtime_us) {
      resolve(*it, &*reg);
      continue;
    }
    if (realtime_us >= it->info.deadline_realtime_us) {
      resolve(*it, static_cast<const RegistrationResult*>(nullptr));
      continue;
    }
    next_check_us_ = std::min(next_check_us_, it->info.deadline_realtime_us);
    if (reg) next_check_us_ = std::min(next_check_us_, reg->available_us);
    if (keep != it) *keep = std::move(*it);
    ++keep;
  }
  pending_.erase(keep, pending_.end());
}

template <class Resolve>
void PendingRegistrations::expire_all(Resolve&& resolve) {
  for (Entry& e : pending_) resolve(e, static_cast<const RegistrationResult*>(nullptr));
  pending_.clear();
}

}  // namespace nav::core
