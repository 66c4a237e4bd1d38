#pragma once
// Provenance of the vision stage's answers (docs/formats.md "Provenance"): only an answer to
// one of this navd run's own link proposals may change the map. LCM multicast carries no
// authentication and a ship's network is shared; the likely accident is an operator replaying
// an earlier dive's log with lcm-logplayer, whose registrations name the same frame ids.
//
// Contract (filter thread only, like the RegistrationTable):
// * Each run draws a random non-zero 64-bit run id (draw_run_id()); every link_proposal_t
//   carries it and its sequence (1, 2, ... in proposal order), and propose() records it.
// * check() classifies an answer (registration_t echoing run_id and sequence) against the
//   pairs the filter still waits for (NavFilter::pending_registrations(), in sequence order:
//   the filter's own view, so a live run applies exactly the answers a replay with the same
//   arrival times would), in this order: kWrongRun (run_id differs), kUnknownSequence
//   (sequence < 1 or never proposed), kAlreadyAnswered (a valid answer for it was taken),
//   kExpired (the filter no longer waits for it: its deadline passed at a measurement before
//   the answer was available, pending_registrations.h), kPairMismatch (frame ids are not the proposal's), else kOurs.
//   Only answered() consumes a sequence, so a rejected answer never uses up its proposal.
// Memory: one bit per proposal of the run.

#include <cstdint>
#include <navlcm/registration_t.hpp>
#include <span>
#include <vector>

#include "nav/core/navigation/pending_registrations.h"

namespace nav::daemon {

enum class Provenance {
  kOurs,
  kWrongRun,
  kUnknownSequence,
  kAlreadyAnswered,
  kExpired,
  kPairMismatch,
};
const char* to_string(Provenance provenance);

/// A random run id from std::random_device (the kernel's getrandom on Linux), never 0.
std::int64_t draw_run_id();

class ProposalLedger {
 public:
  /// run_id != 0 (std::invalid_argument otherwise).
  explicit ProposalLedger(std::int64_t run_id);
  std::int64_t run_id() const { return run_id_; }
  /// A proposal published; sequences must increase (std::invalid_argument).
  void propose(std::uint64_t sequence);
  /// The answer's provenance given the pairs still waiting (contract above); does not consume.
  Provenance check(const navlcm::registration_t& answer,
                   std::span<const core::PendingRegistration> waiting) const;
  /// Marks a kOurs answer's sequence answered (later answers: kAlreadyAnswered).
  void answered(std::uint64_t sequence);
  std::uint64_t last_sequence() const { return last_sequence_; }

 private:
  std::int64_t run_id_;
  std::uint64_t last_sequence_ = 0;
  std::vector<bool> answered_;  ///< by sequence
};

}  // namespace nav::daemon
