// Provenance of registrations: see proposal_ledger.h.
#include "nav/daemon/queue/proposal_ledger.h"

#include <algorithm>
#include <random>
#include <stdexcept>
#include <string>

namespace nav::daemon {

const char* to_string(Provenance provenance) {
  switch (provenance) {
    case Provenance::kOurs: return "ours";
    case Provenance::kWrongRun: return "wrong run";
    case Provenance::kUnknownSequence: return "unknown sequence";
    case Provenance::kAlreadyAnswered: return "already answered";
    case Provenance::kExpired: return "expired";
    case Provenance::kPairMismatch: return "pair mismatch";
  }
  return "?";
}

std::int64_t draw_run_id() {
  std::random_device device;
  std::uint64_t id = 0;
  while (id == 0) {
    id = (static_cast<std::uint64_t>(device()) << 32) ^ static_cast<std::uint64_t>(device());
  }
  return static_cast<std::int64_t>(id);
}

ProposalLedger::ProposalLedger(std::int64_t run_id) : run_id_(run_id) {
  if (run_id == 0) throw std::invalid_argument("ProposalLedger: run id 0 is reserved");
}

void ProposalLedger::propose(std::uint64_t sequence) {
  if (sequence <= last_sequence_) {
    throw std::invalid_argument("ProposalLedger: sequence " + std::to_string(sequence) +
                                " after " + std::to_string(last_sequence_));
  }
  last_sequence_ = sequence;
  if (answered_.size() <= sequence) answered_.resize(sequence + 1 + answered_.size() / 2, false);
}

Provenance ProposalLedger::check(const navlcm::registration_t& answer,
                                 std::span<const core::PendingRegistration> waiting) const {
  if (answer.run_id != run_id_) return Provenance::kWrongRun;
  if (answer.sequence < 1 || static_cast<std::uint64_t>(answer.sequence) > last_sequence_) {
    return Provenance::kUnknownSequence;
  }
  const auto sequence = static_cast<std::uint64_t>(answer.sequence);
  if (answered_[sequence]) return Provenance::kAlreadyAnswered;
  const auto it = std::lower_bound(
      waiting.begin(), waiting.end(), sequence,
      [](const core::PendingRegistration& p, std::uint64_t s) { return p.sequence < s; });
  if (it == waiting.end() || it->sequence != sequence) return Provenance::kExpired;
  if (static_cast<std::int64_t>(it->frame_i) != answer.frame_id_i ||
      static_cast<std::int64_t>(it->frame_j) != answer.frame_id_j) {
    return Provenance::kPairMismatch;
  }
  return Provenance::kOurs;
}

void ProposalLedger::answered(std::uint64_t sequence) {
  if (sequence < answered_.size()) answered_[sequence] = true;
}

}  // namespace nav::daemon
