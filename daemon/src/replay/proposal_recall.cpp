// Proposal recall against the simulator's true overlaps (replay/proposal_recall.h).
#include "nav/daemon/replay/proposal_recall.h"

#include <set>
#include <unordered_map>
#include <utility>

namespace nav::daemon {

std::optional<double> ProposalRecall::recall() const {
  if (true_overlapping == 0) return std::nullopt;
  return static_cast<double>(true_overlapping_proposed) / static_cast<double>(true_overlapping);
}

ProposalRecall proposal_recall(const core::NavFilter& slam,
                               const core::RegistrationTable& registrations,
                               double min_overlap_fraction) {
  std::set<std::pair<std::uint64_t, std::uint64_t>> proposed;
  for (const core::LinkRecord& l : slam.links()) proposed.emplace(l.frame_i, l.frame_j);
  std::unordered_map<std::uint64_t, std::size_t> image_index;  // frame id -> images() index
  const std::vector<core::ImageRecord>& images = slam.images();
  for (std::size_t k = 0; k < images.size(); ++k) image_index.emplace(images[k].frame_id, k);
  ProposalRecall out;
  std::uint64_t proposed_total = 0;
  for (const core::ProposalRecord& row : slam.proposals()) {
    ProposalTruth t;
    proposed_total += static_cast<std::uint64_t>(row.proposed);
    const auto j = image_index.find(row.frame_id);
    for (std::size_t i = 0; j != image_index.end() && i < j->second; ++i) {
      const std::optional<core::RegistrationResult> reg =
          registrations.find(static_cast<std::int64_t>(images[i].frame_id),
                             static_cast<std::int64_t>(row.frame_id));
      if (!reg || reg->overlap_fraction < min_overlap_fraction) continue;
      ++t.true_overlapping;
      if (proposed.count({images[i].frame_id, row.frame_id}) > 0) ++t.true_overlapping_proposed;
    }
    out.true_overlapping += static_cast<std::uint64_t>(t.true_overlapping);
    out.true_overlapping_proposed += static_cast<std::uint64_t>(t.true_overlapping_proposed);
    out.per_image.push_back(t);
  }
  if (!slam.proposals().empty()) {
    out.proposals_per_image_mean =
        static_cast<double>(proposed_total) / static_cast<double>(slam.proposals().size());
  }
  return out;
}

}  // namespace nav::daemon
