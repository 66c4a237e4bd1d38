#pragma once
// How well the link proposal (nav/core/navigation/link_proposer.h) covers the pairs a
// registration could use, in a simulated dive: the simulator's oracle registers every pair
// whose TRUE footprints overlap by at least its min_overlap and states that overlap in each
// registration_t (hil-tests/README.md "Registrations"), so the registration table knows the
// true overlap of every overlapping pair. Per image j: the earlier images whose true overlap
// with j is >= min_overlap_fraction, and how many of them the filter proposed. Recall = their
// totals' ratio (null when no pair overlaps that much, e.g. a real dive without overlaps).

#include <optional>
#include <vector>

#include "nav/core/navigation/nav_filter.h"
#include "nav/core/navigation/registration_table.h"

namespace nav::daemon {

/// The overlap the recall counts: pairs whose true footprints overlap by at least this much.
constexpr double kRecallMinOverlap = 0.2;

struct ProposalTruth {  ///< one image (proposals.csv)
  int true_overlapping = 0;           ///< earlier images overlapping >= kRecallMinOverlap
  int true_overlapping_proposed = 0;  ///< ... of them proposed
};

struct ProposalRecall {
  std::vector<ProposalTruth> per_image;  ///< parallel to NavFilter::proposals()
  std::uint64_t true_overlapping = 0, true_overlapping_proposed = 0;
  double proposals_per_image_mean = 0.0;  ///< proposed pairs / images with a proposal row
  std::optional<double> recall() const;
};

/// Counts for `slam`'s proposals against the overlaps in `registrations` (O(images²) look-ups).
ProposalRecall proposal_recall(const core::NavFilter& slam,
                               const core::RegistrationTable& registrations,
                               double min_overlap_fraction = kRecallMinOverlap);

}  // namespace nav::daemon
