// Writers of the replay output files (output_files.h); headers from output_schema.h.
#include "nav/daemon/replay/output_files.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <utility>

#include "nav/daemon/replay/output_schema.h"

namespace nav::daemon {
namespace {

namespace schema = output_schema;

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

/// Opens `path` for writing and writes the optional comment line and the schema's header row.
File open_csv(const std::filesystem::path& path, const schema::CsvSchema& csv,
              const std::string& comment = {}) {
  File f(std::fopen(path.c_str(), "w"));
  if (!f) throw std::runtime_error("cannot write " + path.string());
  if (!comment.empty()) std::fprintf(f.get(), "%s\n", comment.c_str());
  std::fprintf(f.get(), "%s\n", csv.header().c_str());
  return f;
}

/// Closes `f`, throwing when a write or the close failed (disk full, I/O error).
void close_csv(File f, const std::filesystem::path& path) {
  const bool write_error = std::ferror(f.get()) != 0;
  if (std::fclose(f.release()) != 0 || write_error) {
    throw std::runtime_error("cannot write " + path.string());
  }
}

/// Appends the 36 cells of a 6x6 matrix, row-major (StatesCsv::cell order).
void write_matrix(std::FILE* f, const Eigen::Matrix<double, 6, 6>& m) {
  for (int a = 0; a < 6; ++a) {
    for (int b = 0; b < 6; ++b) std::fprintf(f, ",%.17g", m(a, b));
  }
}

}  // namespace

void write_trajectory_csv(const std::vector<ImageRecord>& images,
                          const std::filesystem::path& path) {
  // dead_reckoning.csv has the same columns as trajectory.csv.
  File f = open_csv(path, schema::TrajectoryCsv::slam());
  for (const ImageRecord& r : images) {
    const core::Vec12& x = r.robot_mean;
    const core::Mat12& P = r.robot_covariance;
    // TrajectoryCsv: t_us, pose, var_x, var_y, var_z, var_heading.
    std::fprintf(f.get(), "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                 static_cast<long long>(r.t_us), x(0), x(1), x(2), x(3), x(4), x(5), P(0, 0),
                 P(1, 1), P(2, 2), P(5, 5));
  }
  close_csv(std::move(f), path);
}

void write_states_csv(const std::vector<StateCheck>& states, const std::filesystem::path& path) {
  File f = open_csv(path, schema::StatesCsv::schema());
  for (const StateCheck& s : states) {
    // StatesCsv: state_id, frame_id, t_us, pose, bound, exact, initial bound.
    std::fprintf(f.get(), "%d,%lld,%lld", s.state,
                 s.image ? static_cast<long long>(s.image->frame_id) : -1LL,
                 s.image ? static_cast<long long>(s.image->t_us) : -1LL);
    for (int k = 0; k < 6; ++k) std::fprintf(f.get(), ",%.17g", s.mean(k));
    write_matrix(f.get(), s.bound);
    write_matrix(f.get(), s.exact);
    write_matrix(f.get(), s.initial_bound);
    std::fprintf(f.get(), "\n");
  }
  close_csv(std::move(f), path);
}

void write_links_csv(const std::vector<LinkRecord>& links, const std::filesystem::path& path) {
  File f = open_csv(path, schema::LinksCsv::schema());
  for (const LinkRecord& l : links) {
    // LinksCsv: t_us, frame_i, frame_j, state_i, state_j, outcome, mahalanobis_sq, is_outlier.
    std::fprintf(f.get(), "%lld,%llu,%llu,%d,%d,%s,", static_cast<long long>(l.t_us),
                 static_cast<unsigned long long>(l.frame_i),
                 static_cast<unsigned long long>(l.frame_j), l.state_i, l.state_j,
                 to_string(l.outcome));
    if (l.mahalanobis_sq >= 0.0) std::fprintf(f.get(), "%.17g", l.mahalanobis_sq);
    std::fprintf(f.get(), ",%d\n", l.is_outlier ? 1 : 0);
  }
  close_csv(std::move(f), path);
}

void write_proposals_csv(const std::vector<ProposalRecord>& rows,
                         const std::vector<ProposalTruth>& truth,
                         const std::filesystem::path& path) {
  File f = open_csv(path, schema::ProposalsCsv::schema());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const ProposalRecord& r = rows[k];
    const ProposalTruth t = k < truth.size() ? truth[k] : ProposalTruth{};
    // ProposalsCsv: frame_id, candidates, proposed, accepted, true_overlapping(_proposed).
    std::fprintf(f.get(), "%llu,%d,%d,%d,%d,%d\n", static_cast<unsigned long long>(r.frame_id),
                 r.candidates, r.proposed, r.accepted, t.true_overlapping,
                 t.true_overlapping_proposed);
  }
  close_csv(std::move(f), path);
}

void write_published_csv(const std::vector<PublishedSolution>& rows,
                         const std::filesystem::path& path) {
  File f = open_csv(path, schema::PublishedCsv::schema());
  for (const PublishedSolution& p : rows) {
    // PublishedCsv: t_us, pose, covariance upper triangle row-major.
    std::fprintf(f.get(), "%lld", static_cast<long long>(p.t_us));
    for (int k = 0; k < 6; ++k) std::fprintf(f.get(), ",%.10g", p.pose(k));
    for (int r = 0; r < 6; ++r) {
      for (int c = r; c < 6; ++c) std::fprintf(f.get(), ",%.10g", p.covariance(r, c));
    }
    std::fprintf(f.get(), "\n");
  }
  close_csv(std::move(f), path);
}

void write_information_blocks_csv(const core::InformationMatrix& info,
                                  const std::filesystem::path& path) {
  using schema::InformationBlocksCsv;
  File f = open_csv(path, InformationBlocksCsv::schema(),
                    InformationBlocksCsv::comment(info.block_dim(), info.num_blocks()));
  for (int i = 0; i < info.num_blocks(); ++i) {
    // InformationBlocksCsv: i, j (i <= j).
    std::fprintf(f.get(), "%d,%d\n", i, i);
    for (int k = 0; k < info.num_neighbours(i); ++k) {
      const int j = info.neighbour(i, k);
      if (i < j) std::fprintf(f.get(), "%d,%d\n", i, j);
    }
  }
  close_csv(std::move(f), path);
}

void write_logdet_csv(const std::vector<LogdetRow>& rows, const std::filesystem::path& path) {
  File f = open_csv(path, schema::LogdetCsv::schema());
  for (const LogdetRow& r : rows) {
    // LogdetCsv: state_i, state_j, ours, markov_blanket.
    std::fprintf(f.get(), "%d,%d,%.17g,%.17g\n", r.state_i, r.state_j, r.ours, r.markov_blanket);
  }
  close_csv(std::move(f), path);
}

void write_time_of_use_csv(const core::TimeOfUseStats& stats,
                           const std::vector<std::uint64_t>& frames,
                           const std::filesystem::path& path) {
  File f = open_csv(path, schema::TimeOfUseCsv::schema());
  for (const core::TimeOfUsePair& p : stats.pairs) {
    // TimeOfUseCsv: frame_id, state, ours, markov_blanket.
    const std::uint64_t frame = frames.at(static_cast<std::size_t>(p.check - 1));
    std::fprintf(f.get(), "%llu,%d,%.17g,", static_cast<unsigned long long>(frame), p.state,
                 p.ours);
    if (!std::isnan(p.markov_blanket)) std::fprintf(f.get(), "%.17g", p.markov_blanket);
    std::fputc('\n', f.get());
  }
  close_csv(std::move(f), path);
}

void write_summary_json(const std::string& summary_json, const std::filesystem::path& path) {
  std::ofstream summary(path);
  if (!(summary << summary_json << "\n")) throw std::runtime_error("cannot write " + path.string());
}

void write_replay_outputs(const ReplayRun& run, const ReplayAnalysis& analysis,
                          const std::string& summary_json, const std::string& dir) {
  const std::filesystem::path out(dir);
  std::filesystem::create_directories(out);
  write_summary_json(summary_json, out / schema::kSummaryFile);
  write_trajectory_csv(run.slam->images(), out / schema::TrajectoryCsv::slam().file());
  if (run.dead_reckoning) {
    write_trajectory_csv(run.dead_reckoning->images(),
                         out / schema::TrajectoryCsv::dead_reckoning().file());
  }
  write_states_csv(analysis.states, out / schema::StatesCsv::schema().file());
  write_links_csv(run.slam->links(), out / schema::LinksCsv::schema().file());
  write_proposals_csv(run.slam->proposals(),
                      proposal_recall(*run.slam, *run.registrations).per_image,
                      out / schema::ProposalsCsv::schema().file());
  write_published_csv(run.published, out / schema::PublishedCsv::schema().file());
  write_information_blocks_csv(run.slam->esdf().information(),
                               out / schema::InformationBlocksCsv::schema().file());
  write_logdet_csv(analysis.logdet, out / schema::LogdetCsv::schema().file());
  write_time_of_use_csv(run.time_of_use, run.time_of_use_frames,
                        out / schema::TimeOfUseCsv::schema().file());
}

}  // namespace nav::daemon
