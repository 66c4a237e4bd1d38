// Readers of the dive directory and replay output files (replay_data.h, hil-tests/README.md).
#include "nav/report/replay_data.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "nav/report/csv_table.h"

namespace nav::report {
namespace fs = std::filesystem;
namespace {

constexpr std::array<const char*, 6> kPoseColumns = {"x_m",      "y_m",       "z_m",
                                                     "roll_rad", "pitch_rad", "heading_rad"};

std::array<size_t, 6> pose_columns(const CsvTable& t) {
  std::array<size_t, 6> cols{};
  for (size_t k = 0; k < 6; ++k) cols[k] = t.column(kPoseColumns[k]);
  return cols;
}

core::Vec6 pose_at(const CsvTable& t, size_t row, const std::array<size_t, 6>& cols) {
  core::Vec6 p;
  for (size_t k = 0; k < 6; ++k) p[static_cast<int>(k)] = t.number(row, cols[k]);
  return p;
}

/// Columns <prefix>00..<prefix>55 (row-major 6x6), or nothing when the first is absent.
std::optional<std::array<size_t, 36>> matrix_columns(const CsvTable& t, char prefix) {
  if (!t.find_column(std::string(1, prefix) + "00")) return std::nullopt;
  std::array<size_t, 36> cols{};
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      cols[static_cast<size_t>(6 * r + c)] =
          t.column(std::string(1, prefix) + std::to_string(r) + std::to_string(c));
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
  const size_t t_col = t.column("t_us");
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
  const size_t id_col = t.column("state_id"), frame_col = t.column("frame_id"),
               t_col = t.column("t_us");
  const auto cols = pose_columns(t);
  const auto b_cols = matrix_columns(t, 'b');
  const auto e_cols = matrix_columns(t, 'e');
  if (!b_cols) t.column("b00");  // throws "missing column"
  if (!e_cols) t.column("e00");
  const auto i_cols = matrix_columns(t, 'i');  // optional: initial bound (Fig. 5)
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
  const size_t t_col = t.column("t_us"), fi = t.column("frame_i"), fj = t.column("frame_j"),
               si = t.column("state_i"), sj = t.column("state_j"), oc = t.column("outcome"),
               m2 = t.column("mahalanobis_sq"), ol = t.column("is_outlier");
  static const std::array<std::string, 4> kOutcomes = {"accepted", "gated", "registration_failed",
                                                       "not_registered"};
  std::vector<ProposedLink> out(t.rows());
  for (size_t r = 0; r < t.rows(); ++r) {
    ProposedLink& l = out[r];
    l.t_us = t.integer(r, t_col);
    l.frame_i = t.integer(r, fi);
    l.frame_j = t.integer(r, fj);
    l.state_i = t.integer(r, si);
    l.state_j = t.integer(r, sj);
    l.outcome = t.text(r, oc);
    if (std::find(kOutcomes.begin(), kOutcomes.end(), l.outcome) == kOutcomes.end()) {
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
      if (!have_dims && c >> k1 >> p.block_dim >> k2 >> p.num_blocks && k1 == "block_dim" &&
          k2 == "num_blocks") {
        have_dims = true;
      } else if (!have_dims) {
        throw ReportError(where() + ": expected '# block_dim D num_blocks N', got '" + line + "'");
      }
      continue;
    }
    if (line == "i,j") continue;  // optional header row
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
  const size_t si = t.column("state_i"), sj = t.column("state_j"), ours = t.column("ours"),
               mb = t.column("markov_blanket");
  std::vector<LogdetRow> out(t.rows());
  for (size_t r = 0; r < t.rows(); ++r) {
    out[r] = {t.integer(r, si), t.integer(r, sj), t.number(r, ours), t.number(r, mb)};
  }
  return out;
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

ReplayOutput read_replay_output(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw ReportError(dir.string() + ": not a directory");
  ReplayOutput out;
  out.dir = dir;
  out.summary =
      fs::exists(dir / "summary.json") ? read_json(dir / "summary.json") : nlohmann::json::object();
  out.trajectory = read_timed_poses(dir / "trajectory.csv");
  out.dead_reckoning = read_timed_poses(dir / "dead_reckoning.csv");
  out.states = read_states(dir / "states.csv");
  out.links = read_links(dir / "links.csv");
  if (fs::exists(dir / "proposals.csv")) {
    out.proposal_rows = static_cast<long long>(CsvTable::read(dir / "proposals.csv").rows());
  }
  if (fs::exists(dir / "information_blocks.csv")) {
    out.blocks = read_block_pattern(dir / "information_blocks.csv");
  }
  if (fs::exists(dir / "logdet.csv")) out.logdet = read_logdet(dir / "logdet.csv");
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
