#pragma once
// Registrations arriving while navd runs (live mode: the vision stage's registration_t on LCM)
// on their way to the filter thread, which owns the RegistrationTable the NavFilter reads.
//
// Contract:
// * offer() is called by ONE producer thread (the LCM listener); it never blocks and never
//   allocates: a bounded single-producer/single-consumer moodycamel::ReaderWriterQueue with
//   at least `capacity` slots preallocated (it rounds up); an offer into a full queue is dropped
//   and counted.
// * drain(), ledger() and table() belong to the filter thread (no locks in the filter path):
//   drain() inserts what arrived into the table before the filter processes the next
//   measurements. First the answer's provenance (proposal_ledger.h): one that does not answer
//   an open proposal of this run is counted by reason and never reaches the table.
//   A pair already in the table keeps its first answer (counted `duplicates`); an answer that
//   core::registration_problem() refuses (frame ids out of order; a non-finite or out-of-range
//   measurement; a non-finite, asymmetric or indefinite covariance) is counted `invalid` and
//   logged with the reason, never applied and never thrown into the filter thread.
// * A registration for a pair the filter never proposes just stays in the table (`unknown` to
//   the filter: nav/core/navigation/pending_registrations.h).

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <navlcm/registration_t.hpp>

#include "nav/daemon/filter/registration_message.h"
#include "nav/daemon/queue/proposal_ledger.h"

namespace nav::daemon {

struct RegistrationInboxCounters {
  std::uint64_t received = 0;    ///< offered and queued
  std::uint64_t dropped = 0;     ///< offered while the queue was full
  std::uint64_t inserted = 0;    ///< new pairs in the table
  std::uint64_t duplicates = 0;  ///< pair already registered (first answer kept)
  std::uint64_t invalid = 0;     ///< core::registration_problem() refused it
  /// Provenance rejections (proposal_ledger.h), as of the last drain().
  std::uint64_t wrong_run = 0, unknown_sequence = 0, already_answered = 0, expired = 0;
  std::uint64_t pair_mismatch = 0;
};

class RegistrationInbox {
 public:
  /// `capacity` >= 1 queued registrations, `run_id` != 0 this run's id (std::invalid_argument
  /// otherwise).
  RegistrationInbox(std::size_t capacity, std::int64_t run_id);
  ~RegistrationInbox();
  RegistrationInbox(const RegistrationInbox&) = delete;
  RegistrationInbox& operator=(const RegistrationInbox&) = delete;

  /// Producer thread: queues one registration; false (counted) when full.
  bool offer(const navlcm::registration_t& registration);
  /// Filter thread: whether anything is queued (drain() has work).
  bool has_queued() const;
  /// Filter thread: moves everything queued that answers a proposal of this run the filter
  /// still waits for (`waiting`: NavFilter::pending_registrations()) into the table; the
  /// number taken off the queue.
  std::size_t drain(std::span<const core::PendingRegistration> waiting);
  /// Filter thread: the proposals this run published (the proposal publisher records them).
  ProposalLedger& ledger() { return ledger_; }
  /// Filter thread: the table the NavFilter reads (stable address for the inbox's lifetime).
  const RegistrationTable& table() const { return table_; }
  /// Any thread (received/dropped exact; the filter-side counts as of the last drain()).
  RegistrationInboxCounters counters() const;

 private:
  struct Queue;
  std::unique_ptr<Queue> queue_;
  void reject(Provenance provenance, const navlcm::registration_t& answer);
  RegistrationTable table_;
  ProposalLedger ledger_;
  std::atomic<std::uint64_t> received_{0}, dropped_{0};
  std::atomic<std::uint64_t> inserted_{0}, duplicates_{0}, invalid_{0};
  std::atomic<std::uint64_t> wrong_run_{0}, unknown_sequence_{0}, already_answered_{0},
      expired_{0}, pair_mismatch_{0};
};

}  // namespace nav::daemon
