#pragma once
// Writers of the replay output directory's files, one per file, each taking the plain records it
// writes (so that a test can write every file without running a replay). Header rows and column
// order come from output_schema.h; numbers are written with %.17g (round-trip exact), ids and
// times as integers. Each throws std::runtime_error naming the file that cannot be written.
// write_replay_outputs (dive_replay.h) calls them for a whole replay.

#include <filesystem>
#include <string>
#include <vector>

#include "nav/core/filter/information_matrix.h"
#include "nav/core/navigation/nav_filter.h"
#include "nav/daemon/replay/dive_replay.h"
#include "nav/daemon/replay/proposal_recall.h"

namespace nav::daemon {

/// trajectory.csv / dead_reckoning.csv: one row per image (robot mean and Σ_rr diagonal).
void write_trajectory_csv(const std::vector<ImageRecord>& images,
                          const std::filesystem::path& path);
/// states.csv: one row per delayed state of the final analysis.
void write_states_csv(const std::vector<StateCheck>& states, const std::filesystem::path& path);
/// links.csv: one row per proposed pair; mahalanobis_sq empty when negative (never gated).
void write_links_csv(const std::vector<LinkRecord>& links, const std::filesystem::path& path);
/// proposals.csv: one row per image; `truth` parallel to `rows` (missing rows: 0, 0).
void write_proposals_csv(const std::vector<ProposalRecord>& rows,
                         const std::vector<ProposalTruth>& truth,
                         const std::filesystem::path& path);
/// published.csv: one row per published solution (numbers with %.10g: ~70k rows a dive).
void write_published_csv(const std::vector<PublishedSolution>& rows,
                         const std::filesystem::path& path);
/// information_blocks.csv: the block pattern of `info` (i <= j).
void write_information_blocks_csv(const core::InformationMatrix& info,
                                  const std::filesystem::path& path);
/// logdet.csv: one row per log-det ratio row.
void write_logdet_csv(const std::vector<LogdetRow>& rows, const std::filesystem::path& path);
/// time_of_use.csv: one row per pair of `stats`, frames[c - 1] the frame of check c (header
/// only without checks).
void write_time_of_use_csv(const core::TimeOfUseStats& stats,
                           const std::vector<std::uint64_t>& frames,
                           const std::filesystem::path& path);
/// summary.json: `summary_json` and a newline.
void write_summary_json(const std::string& summary_json, const std::filesystem::path& path);

}  // namespace nav::daemon
