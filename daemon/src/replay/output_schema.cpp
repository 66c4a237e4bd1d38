// The replay output directory's column schemas: see output_schema.h.
#include "nav/daemon/replay/output_schema.h"

#include <stdexcept>
#include <utility>

namespace nav::daemon::output_schema {
namespace {

/// x_m .. heading_rad, the order of the pose part of the 12-dof state (core/README.md).
void append_pose(std::vector<Column>& columns) {
  for (Column c : {Column{"x_m", "m"}, Column{"y_m", "m"}, Column{"z_m", "m"},
                   Column{"roll_rad", "rad"}, Column{"pitch_rad", "rad"},
                   Column{"heading_rad", "rad"}}) {
    columns.push_back(std::move(c));
  }
}

/// <prefix>00 .. <prefix>55, row-major; units of the pose covariance cells (m·m, m·rad, ...).
void append_matrix(std::vector<Column>& columns, char prefix) {
  const char* kAxisUnit[6] = {"m", "m", "m", "rad", "rad", "rad"};
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      const std::string unit = kAxisUnit[r] == std::string(kAxisUnit[c])
                                   ? std::string(kAxisUnit[r]) + "2"
                                   : std::string(kAxisUnit[r]) + "*" + kAxisUnit[c];
      columns.push_back({std::string(1, prefix) + std::to_string(r) + std::to_string(c), unit});
    }
  }
}

std::vector<Column> trajectory_columns() {
  std::vector<Column> c{{"t_us", "us"}};
  append_pose(c);
  c.insert(c.end(), {{"var_x", "m2"}, {"var_y", "m2"}, {"var_z", "m2"}, {"var_heading", "rad2"}});
  return c;
}

}  // namespace

CsvSchema::CsvSchema(std::string file, std::vector<Column> columns)
    : file_(std::move(file)), columns_(std::move(columns)) {}

const std::string& CsvSchema::name(std::size_t index) const {
  if (index >= columns_.size()) {
    throw std::out_of_range(file_ + ": no column " + std::to_string(index) + " (has " +
                            std::to_string(columns_.size()) + ")");
  }
  return columns_[index].name;
}

std::string CsvSchema::header() const {
  std::string out;
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (i > 0) out += ',';
    out += columns_[i].name;
  }
  return out;
}

const CsvSchema& TrajectoryCsv::slam() {
  static const CsvSchema schema("trajectory.csv", trajectory_columns());
  return schema;
}

const CsvSchema& TrajectoryCsv::dead_reckoning() {
  static const CsvSchema schema("dead_reckoning.csv", trajectory_columns());
  return schema;
}

const CsvSchema& StatesCsv::schema() {
  static const CsvSchema schema("states.csv", [] {
    std::vector<Column> c{{"state_id", ""}, {"frame_id", ""}, {"t_us", "us"}};
    append_pose(c);
    append_matrix(c, 'b');
    append_matrix(c, 'e');
    append_matrix(c, 'i');
    return c;
  }());
  return schema;
}

const CsvSchema& LinksCsv::schema() {
  static const CsvSchema schema(
      "links.csv", {{"t_us", "us"},
                    {"frame_i", ""},
                    {"frame_j", ""},
                    {"state_i", ""},
                    {"state_j", ""},
                    {"outcome", ""},
                    {"mahalanobis_sq", ""},
                    {"is_outlier", ""}});
  return schema;
}

const CsvSchema& ProposalsCsv::schema() {
  static const CsvSchema schema(
      "proposals.csv",
      {{"frame_id", ""},
       {"candidates", ""},
       {"proposed", ""},
       {"accepted", ""},
       {"true_overlapping", ""},
       {"true_overlapping_proposed", ""}});
  return schema;
}

const CsvSchema& PublishedCsv::schema() {
  static const CsvSchema schema("published.csv", [] {
    std::vector<Column> c{{"t_us", "us"}};
    append_pose(c);
    std::vector<Column> full;
    append_matrix(full, 'c');
    for (int r = 0; r < 6; ++r) {
      for (int col = r; col < 6; ++col) c.push_back(full[static_cast<std::size_t>(6 * r + col)]);
    }
    return c;
  }());
  return schema;
}

std::string InformationBlocksCsv::comment(int block_dim, int num_blocks) {
  return "# " + std::string(kBlockDimKey) + " " + std::to_string(block_dim) + " " +
         std::string(kNumBlocksKey) + " " + std::to_string(num_blocks);
}

const CsvSchema& InformationBlocksCsv::schema() {
  static const CsvSchema schema("information_blocks.csv", {{"i", ""}, {"j", ""}});
  return schema;
}

const CsvSchema& LogdetCsv::schema() {
  static const CsvSchema schema(
      "logdet.csv", {{"state_i", ""}, {"state_j", ""}, {"ours", ""}, {"markov_blanket", ""}});
  return schema;
}

const CsvSchema& TimeOfUseCsv::schema() {
  static const CsvSchema schema(
      "time_of_use.csv", {{"frame_id", ""}, {"state", ""}, {"ours", ""}, {"markov_blanket", ""}});
  return schema;
}

}  // namespace nav::daemon::output_schema
