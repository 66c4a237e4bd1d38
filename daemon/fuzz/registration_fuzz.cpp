// libFuzzer target for navd's registration path, the one input the vision stage sends over LCM
// (a trust boundary: multicast, unauthenticated): bytes -> registration_t decode -> signature
// check -> RegistrationInbox (provenance against a fixed set of proposals, then
// core::registration_problem) -> RegistrationTable. Nothing may crash or throw; an answer the
// table took must be one whose provenance was this run's and whose values are finite, with
// a positive definite covariance; the counters must add up.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "nav/daemon/filter/registration_signature.h"
#include "nav/daemon/queue/registration_inbox.h"

namespace {

constexpr std::int64_t kRun = 0x0123'4567'89ab'cdef;

/// Aborts (a finding for libFuzzer) naming the broken property when `condition` is false.
#define NAV_FUZZ_CHECK(condition)                                                   \
  do {                                                                     \
    if (!(condition)) {                                                    \
      std::fprintf(stderr, "registration_fuzz: %s is false\n", #condition); \
      std::abort();                                                        \
    }                                                                      \
  } while (false)

std::vector<nav::core::PendingRegistration> waiting() {
  std::vector<nav::core::PendingRegistration> out;
  for (std::uint64_t s = 1; s <= 4; ++s) {  // sequences 1..4 wait for pairs (s, s + 1)
    nav::core::PendingRegistration p;
    p.sequence = s;
    p.frame_i = s;
    p.frame_j = s + 1;
    p.deadline_realtime_us = 1'000'000;
    out.push_back(p);
  }
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* bytes, size_t size) {
  navlcm::registration_t r;
  if (r.decode(bytes, 0, static_cast<int>(size)) < 0) return 0;
  static const nav::daemon::SigningKey key =
      nav::daemon::signing_key_from_hex("000102030405060708090a0b0c0d0e0f");
  nav::daemon::SignatureChecker signatures(key, 1'000'000);
  (void)signatures.check(r, r.signature_time_us);  // any verdict, never a crash
  static const std::vector<nav::core::PendingRegistration> pending = waiting();
  nav::daemon::RegistrationInbox inbox(4, kRun);
  for (const auto& p : pending) inbox.ledger().propose(p.sequence);
  // The decoded answer as it came, and as an answer of this run to the proposal it names
  // (so the values reach core::registration_problem whatever the run id and sequence).
  navlcm::registration_t ours = r;
  ours.run_id = kRun;
  if (r.sequence < 1 || r.sequence > 4) ours.sequence = 1 + (r.frame_id_i & 3);
  NAV_FUZZ_CHECK(inbox.offer(r));
  NAV_FUZZ_CHECK(inbox.offer(ours));
  NAV_FUZZ_CHECK(inbox.drain(pending) == 2);
  const nav::daemon::RegistrationInboxCounters c = inbox.counters();
  NAV_FUZZ_CHECK(c.inserted + c.duplicates + c.invalid + c.wrong_run + c.unknown_sequence +
            c.already_answered + c.expired + c.pair_mismatch ==
        2);
  NAV_FUZZ_CHECK(inbox.table().size() == c.inserted);
  if (c.inserted > 0) {
    const auto got = inbox.table().find(r.frame_id_i, r.frame_id_j);
    NAV_FUZZ_CHECK(got.has_value());
    NAV_FUZZ_CHECK(r.frame_id_i < r.frame_id_j);
    if (got->success) {
      NAV_FUZZ_CHECK(got->z.allFinite() && got->covariance.allFinite());
      for (int k = 0; k < 5; ++k) NAV_FUZZ_CHECK(got->covariance(k, k) > 0.0);
    }
  }
  return 0;
}
