// Readers of the dive directory and replay output files (replay_data.h, hil-tests/README.md).
// The replay output files are read by the column names of their schemas (output_schema.h), the
// same the writer derives its header rows from.
#include "nav/report/replay_data.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "nav/daemon/replay/output_schema.h"
#include "nav/report/csv_table.h"

namespace nav::report {
namespace fs = std::filesystem;
namespace schema = daemon::output_schema;
using schema::InformationBlocksCsv;
using schema::LinksCsv;
using schema::LogdetCsv;
using schema::StatesCsv;
using schema::TrajectoryCsv;
namespace {

/// Columns x_m .. heading_rad. The dive directory's truth.csv and images.csv name them as the
/// replay output files do.
std::array<size_t, 6> pose_columns(const CsvTable& t) {
  const schema::CsvSchema& names = TrajectoryCsv::slam();
  std::array<size_t, 6> cols{};
  for (size_t k = 0; k < 6; ++k) cols[k] = t.column(names.name(TrajectoryCsv::kPose + k));
  return cols;
}

/// Index in `t` of column `index` of `csv` ("missing column" error when absent).
size_t column(const CsvTable& t, const schema::CsvSchema& csv, size_t index) {
  return t.column(csv.name(index));
}

core::Vec6 pose_at(const CsvTable& t, size_t row, const std::array<size_t, 6>& cols) {
  core::Vec6 p;
  for (size_t k = 0; k < 6; ++k) p[static_cast<int>(k)] = t.number(row, cols[k]);
  return p;
}

/// The 36 columns of the states.csv matrix starting at `first` (StatesCsv::kBound, kExact,
/// kInitialBound; row-major 6x6), or nothing when its first cell's column is absent.
std::optional<std::array<size_t, 36>> matrix_columns(const CsvTable& t, size_t first) {
  const schema::CsvSchema& csv = StatesCsv::schema();
  if (!t.find_column(csv.name(first))) return std::nullopt;
  std::array<size_t, 36> cols{};
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      cols[static_cast<size_t>(6 * r + c)] = column(t, csv, StatesCsv::cell(first, r, c));
    }
  }
  return cols;
}

core::Mat6 matrix_at(const CsvTable& t, size_t row, const std::array<size_t, 36>& cols) {
  core::Mat6 m;
  for (int k = 0; k < 36; ++k) m(k / 6, k % 6) = t.number(row, cols[static_cast<size_t>(k)]);
  return m;
}

/// Rows must be in non-decreasing time (interpolation and "final" rely on it).
void require_time_order(const CsvTable& t, size_t row, long long prev_t_us, long long t_us) {
  if (row > 0 && t_us < prev_t_us) {
    throw ReportError(t.where(row) + ": t_us " + std::to_string(t_us) +
                      " goes back in time (previous row " + std::to_string(prev_t_us) + ")");
  }
}

bool parse_integer(const std::string& s, long long& value) {
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  return !s.empty() && ec == std::errc() && end == s.data() + s.size();
}

}  // namespace

std::vector<TimedPose> read_timed_poses(const fs::path& file) {
  const CsvTable t = CsvTable::read(file);
  const size_t t_col = column(t, TrajectoryCsv::slam(), TrajectoryCsv::kTimeUs);
  const auto cols = pose_columns(t);
  std::vector<TimedPose> out(t.rows());
  for (size_t r = 0; r < t.rows(); ++r) {
    out[r].t_us = t.integer(r, t_col);
    out[r].pose = pose_at(t, r, cols);
    require_time_order(t, r, r > 0 ? out[r - 1].t_us : 0, out[r].t_us);
  }
  return out;
}

std::vector<TrueImage> read_images(const fs::path& file) {
  const CsvTable t = CsvTable::read(file);
  const size_t id_col = t.column("frame_id"), t_col = t.column("t_us");
  const auto cols = pose_columns(t);
  std::vector<TrueImage> out(t.rows());
  for (size_t r = 0; r < t.rows(); ++r) {
    out[r].frame_id = t.integer(r, id_col);
    out[r].t_us = t.integer(r, t_col);
    out[r].pose = pose_at(t, r, cols);
  }
  return out;
}

std::vector<DelayedState> read_states(const fs::path& file) {
  const CsvTable t = CsvTable::read(file);
  const schema::CsvSchema& csv = StatesCsv::schema();
  const size_t id_col = column(t, csv, StatesCsv::kStateId),
               frame_col = column(t, csv, StatesCsv::kFrameId),
               t_col = column(t, csv, StatesCsv::kTimeUs);
  const auto cols = pose_columns(t);
  const auto b_cols = matrix_columns(t, StatesCsv::kBound);
  const auto e_cols = matrix_columns(t, StatesCsv::kExact);
  if (!b_cols) column(t, csv, StatesCsv::kBound);  // throws "missing column"
  if (!e_cols) column(t, csv, StatesCsv::kExact);
  const auto i_cols = matrix_columns(t, StatesCsv::kInitialBound);  // optional (Fig. 5)
  std::vector<DelayedState> out(t.rows());
  for (size_t r = 0; r < t.rows(); ++r) {
    DelayedState& s = out[r];
    s.state_id = t.integer(r, id_col);
    s.frame_id = t.integer(r, frame_col);
    s.t_us = t.integer(r, t_col);
    s.pose = pose_at(t, r, cols);
    s.bound = matrix_at(t, r, *b_cols);
    s.exact = matrix_at(t, r, *e_cols);
    if (i_cols) s.initial = matrix_at(t, r, *i_cols);
  }
  std::sort(out.begin(), out.end(),
            [](const DelayedState& a, const DelayedState& b) { return a.state_id < b.state_id; });
  return out;
}

std::vector<ProposedLink> read_links(const fs::path& file) {
  const CsvTable t = CsvTable::read(file);
  const schema::CsvSchema& csv = LinksCsv::schema();
  const size_t t_col = column(t, csv, LinksCsv::kTimeUs), fi = column(t, csv, LinksCsv::kFrameI),
               fj = column(t, csv, LinksCsv::kFrameJ), si = column(t, csv, LinksCsv::kStateI),
               sj = column(t, csv, LinksCsv::kStateJ), oc = column(t, csv, LinksCsv::kOutcome),
               m2 = column(t, csv, LinksCsv::kMahalanobisSq),
               ol = column(t, csv, LinksCsv::kIsOutlier);
  const auto& kOutcomes = LinksCsv::kOutcomes;
  std::vector<ProposedLink> out(t.rows());
  for (size_t r = 0; r < t.rows(); ++r) {
    ProposedLink& l = out[r];
    l.t_us = t.integer(r, t_col);
    l.frame_i = t.integer(r, fi);
    l.frame_j = t.integer(r, fj);
    l.state_i = t.integer(r, si);
    l.state_j = t.integer(r, sj);
    l.outcome = t.text(r, oc);
    if (std::find(std::begin(kOutcomes), std::end(kOutcomes), l.outcome) == std::end(kOutcomes)) {
      throw ReportError(t.where(r) + ": column 'outcome': '" + l.outcome +
                        "' is not one of accepted, gated, registration_failed, not_registered");
    }
    // A pair that was never registered or failed has no Mahalanobis distance: allow empty/nan.
    const std::string& m = t.text(r, m2);
    l.mahalanobis_sq = (m.empty() || m == "nan" || m == "NaN") ? std::nan("") : t.number(r, m2);
    l.is_outlier = t.boolean(r, ol);
  }
  return out;
}

BlockPattern read_block_pattern(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ReportError(file.string() + ": cannot open");
  BlockPattern p;
  bool have_dims = false;
  int line_no = 0;
  auto where = [&] { return file.string() + ":" + std::to_string(line_no); };
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    if (line[0] == '#') {
      std::istringstream c(line.substr(1));
      std::string k1, k2;
      if (!have_dims && c >> k1 >> p.block_dim >> k2 >> p.num_blocks &&
          k1 == InformationBlocksCsv::kBlockDimKey && k2 == InformationBlocksCsv::kNumBlocksKey) {
        have_dims = true;
      } else if (!have_dims) {
        throw ReportError(where() + ": expected '# block_dim D num_blocks N', got '" + line + "'");
      }
      continue;
    }
    if (line == InformationBlocksCsv::schema().header()) continue;  // optional header row
    const size_t comma = line.find(',');
    long long i = 0, j = 0;
    if (comma == std::string::npos || !parse_integer(line.substr(0, comma), i) ||
        !parse_integer(line.substr(comma + 1), j)) {
      throw ReportError(where() + ": '" + line + "' is not 'i,j' (two integers)");
    }
    if (i < 0 || j < i) throw ReportError(where() + ": block (" + line + ") needs 0 <= i <= j");
    p.blocks.emplace_back(i, j);
  }
  if (!have_dims) throw ReportError(file.string() + ": no '# block_dim D num_blocks N' line");
  if (p.block_dim <= 0 || p.num_blocks <= 0) {
    throw ReportError(file.string() + ": block_dim and num_blocks must be positive");
  }
  for (const auto& [i, j] : p.blocks) {
    if (j >= p.num_blocks) {
      throw ReportError(file.string() + ": block (" + std::to_string(i) + "," + std::to_string(j) +
                        ") outside num_blocks " + std::to_string(p.num_blocks));
    }
  }
  return p;
}

std::vector<LogdetRow> read_logdet(const fs::path& file) {
  const CsvTable t = CsvTable::read(file);
  const schema::CsvSchema& csv = LogdetCsv::schema();
  const size_t si = column(t, csv, LogdetCsv::kStateI), sj = column(t, csv, LogdetCsv::kStateJ),
               ours = column(t, csv, LogdetCsv::kOurs),
               mb = column(t, csv, LogdetCsv::kMarkovBlanket);
  std::vector<LogdetRow> out(t.rows());
  for (size_t r = 0; r < t.rows(); ++r) {
    out[r] = {t.integer(r, si), t.integer(r, sj), t.number(r, ours), t.number(r, mb)};
  }
  return out;
}

std::vector<TimeOfUseRow> read_time_of_use(const fs::path& file) {
  const CsvTable t = CsvTable::read(file);
  const schema::CsvSchema& csv = schema::TimeOfUseCsv::schema();
  const size_t frame = column(t, csv, schema::TimeOfUseCsv::kFrameId),
               state = column(t, csv, schema::TimeOfUseCsv::kState),
               ours = column(t, csv, schema::TimeOfUseCsv::kOurs),
               mb = column(t, csv, schema::TimeOfUseCsv::kMarkovBlanket);
  std::vector<TimeOfUseRow> out(t.rows());
  for (size_t r = 0; r < t.rows(); ++r) {
    const double blanket =
        t.text(r, mb).empty() ? std::numeric_limits<double>::quiet_NaN() : t.number(r, mb);
    out[r] = {t.integer(r, frame), t.integer(r, state), t.number(r, ours), blanket};
  }
  return out;
}

daemon::ReplaySummary read_summary(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ReportError(file.string() + ": cannot open");
  std::stringstream text;
  text << in.rdbuf();
  try {
    return daemon::ReplaySummary::from_json(text.str(), file.string());
  } catch (const std::invalid_argument& e) {
    throw ReportError(e.what());
  }
}

nlohmann::json read_json(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ReportError(file.string() + ": cannot open");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw ReportError(file.string() + ": not valid JSON: " + e.what());
  }
}

std::vector<daemon::PublishedSolution> read_published(const fs::path& file) {
  using schema::PublishedCsv;
  const CsvTable t = CsvTable::read(file);
  const schema::CsvSchema& csv = PublishedCsv::schema();
  const size_t t_col = column(t, csv, PublishedCsv::kTimeUs);
  const auto cols = pose_columns(t);
  std::array<size_t, 21> cov_cols{};
  for (int r = 0, k = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) cov_cols[static_cast<size_t>(k++)] = column(t, csv, PublishedCsv::cell(r, c));
  }
  std::vector<daemon::PublishedSolution> out(t.rows());
  for (size_t row = 0; row < t.rows(); ++row) {
    daemon::PublishedSolution& p = out[row];
    p.t_us = t.integer(row, t_col);
    p.pose = pose_at(t, row, cols);
    for (int r = 0, k = 0; r < 6; ++r) {
      for (int c = r; c < 6; ++c) {
        p.covariance(r, c) = p.covariance(c, r) = t.number(row, cov_cols[static_cast<size_t>(k++)]);
      }
    }
  }
  return out;
}

ReplayOutput read_replay_output(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw ReportError(dir.string() + ": not a directory");
  ReplayOutput out;
  out.dir = dir;
  if (const fs::path summary = dir / schema::kSummaryFile; fs::exists(summary)) {
    out.summary = read_summary(summary);
  }
  out.trajectory = read_timed_poses(dir / TrajectoryCsv::slam().file());
  out.dead_reckoning = read_timed_poses(dir / TrajectoryCsv::dead_reckoning().file());
  out.states = read_states(dir / StatesCsv::schema().file());
  out.links = read_links(dir / LinksCsv::schema().file());
  if (const fs::path proposals = dir / schema::ProposalsCsv::schema().file();
      fs::exists(proposals)) {
    const CsvTable t = CsvTable::read(proposals);
    out.proposal_rows = static_cast<long long>(t.rows());
    const schema::CsvSchema& csv = schema::ProposalsCsv::schema();
    const size_t proposed = column(t, csv, schema::ProposalsCsv::kProposed);
    const auto truth = t.find_column(csv.name(schema::ProposalsCsv::kTrueOverlapping));
    const auto found =
        t.find_column(csv.name(schema::ProposalsCsv::kTrueOverlappingProposed));
    for (size_t r = 0; r < t.rows(); ++r) {
      out.proposed += t.integer(r, proposed);
      if (truth && found) {
        out.true_overlapping += t.integer(r, *truth);
        out.true_overlapping_proposed += t.integer(r, *found);
      }
    }
  }
  if (const fs::path published = dir / schema::PublishedCsv::schema().file();
      fs::exists(published)) {
    out.published = read_published(published);
  }
  if (const fs::path blocks = dir / InformationBlocksCsv::schema().file(); fs::exists(blocks)) {
    out.blocks = read_block_pattern(blocks);
  }
  if (const fs::path logdet = dir / LogdetCsv::schema().file(); fs::exists(logdet)) {
    out.logdet = read_logdet(logdet);
  }
  if (const fs::path t = dir / schema::TimeOfUseCsv::schema().file(); fs::exists(t)) {
    out.time_of_use = read_time_of_use(t);
  }
  return out;
}

DiveData read_dive(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw ReportError(dir.string() + ": not a directory");
  DiveData d;
  d.dir = dir;
  d.truth = read_timed_poses(dir / "truth.csv");
  if (d.truth.empty()) throw ReportError((dir / "truth.csv").string() + ": no rows");
  if (fs::exists(dir / "images.csv")) d.images = read_images(dir / "images.csv");
  d.sim = fs::exists(dir / "sim.json") ? read_json(dir / "sim.json") : nlohmann::json::object();
  return d;
}

}  // namespace nav::report
