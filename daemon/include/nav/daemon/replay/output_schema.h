#pragma once
// The column schemas of the replay output directory (hil-tests/README.md "Replay output
// directory"): for every CSV file its name, its columns in header order and their units. The
// writer (output_files.h) derives each header row from these schemas and writes the cells in
// the order of the column enums; the report's readers (nav/report/replay_data.h) look every
// column up by the same names. One definition, so a column renamed, added or reordered changes
// writer and reader together (daemon/tests/replay_output_schema_test.cpp writes every file and
// reads it back).
//
// Units: "us" host or data time in microseconds, "m" metres (world NED), "rad" radians,
// "m2"/"rad2" variances, "" ids, counts and dimensionless numbers.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace nav::daemon::output_schema {

/// One column of a CSV file.
struct Column {
  std::string name;  ///< as written in the header row
  std::string unit;  ///< see above; "" for ids, counts, flags and dimensionless values
};

/// One CSV file of the replay output directory.
class CsvSchema {
 public:
  CsvSchema(std::string file, std::vector<Column> columns);

  const std::string& file() const { return file_; }
  const std::vector<Column>& columns() const { return columns_; }
  std::size_t size() const { return columns_.size(); }
  /// Name of column `index` (an enumerator of the file's Index enum below); throws
  /// std::out_of_range naming the file when there is no such column.
  const std::string& name(std::size_t index) const;
  /// The header row: the names joined by ',' (no newline).
  std::string header() const;

 private:
  std::string file_;
  std::vector<Column> columns_;
};

/// summary.json: one JSON object (ReplaySummary, replay_summary.h).
inline constexpr std::string_view kSummaryFile = "summary.json";

/// The six pose columns x_m, y_m, z_m, roll_rad, pitch_rad, heading_rad start at kPose in every
/// file that has a pose (trajectory, dead reckoning, states); offsets 0..5 in that order.
inline constexpr std::size_t kPoseDim = 6;

/// trajectory.csv and dead_reckoning.csv: the robot estimate after each image.
struct TrajectoryCsv {
  enum Index : std::size_t {
    kTimeUs,       ///< t_us: the image's time of validity
    kPose,         ///< x_m .. heading_rad (kPoseDim columns)
    kVarX = kPose + kPoseDim,  ///< var_x: Σ_rr(0,0)
    kVarY,         ///< var_y: Σ_rr(1,1)
    kVarZ,         ///< var_z: Σ_rr(2,2)
    kVarHeading,   ///< var_heading: Σ_rr(5,5)
    kCount
  };
  static const CsvSchema& slam();            ///< trajectory.csv
  static const CsvSchema& dead_reckoning();  ///< dead_reckoning.csv (same columns)
};

/// states.csv: one row per delayed state at the end: the final mean and three 6x6 pose
/// covariances (row-major, 36 columns each, named <prefix><row><col>: b00 .. b55).
struct StatesCsv {
  static constexpr std::size_t kMatrixCells = 36;
  enum Index : std::size_t {
    kStateId,   ///< state_id: filter block (1.. ; 0 is the robot)
    kFrameId,   ///< frame_id: the image's frame id (-1 when unknown)
    kTimeUs,    ///< t_us: the image's time (-1 when unknown)
    kPose,      ///< x_m .. heading_rad: final recovered mean
    kBound = kPose + kPoseDim,             ///< b00..b55: stored conservative bound
    kExact = kBound + kMatrixCells,        ///< e00..e55: exact marginal
    kInitialBound = kExact + kMatrixCells, ///< i00..i55: bound at insertion (optional to readers)
    kCount = kInitialBound + kMatrixCells
  };
  /// Index of cell (row, col) of the matrix starting at `first` (kBound, kExact, kInitialBound).
  static constexpr std::size_t cell(std::size_t first, int row, int col) {
    return first + static_cast<std::size_t>(6 * row + col);
  }
  static const CsvSchema& schema();
};

/// links.csv: one row per proposed pair.
struct LinksCsv {
  enum Index : std::size_t {
    kTimeUs,          ///< t_us: time of the later image
    kFrameI,          ///< frame_i: earlier image
    kFrameJ,          ///< frame_j: later image
    kStateI,          ///< state_i: filter block of the earlier image
    kStateJ,          ///< state_j: filter block of the later image (-1 when not kept)
    kOutcome,         ///< outcome: one of kOutcomes
    kMahalanobisSq,   ///< mahalanobis_sq: 5-dof gate statistic, empty when never registered
    kIsOutlier,       ///< is_outlier: 1/0, the registration's simulator truth
    kCount
  };
  static constexpr std::string_view kOutcomes[] = {"accepted", "gated", "registration_failed",
                                                   "not_registered"};
  static const CsvSchema& schema();
};

/// proposals.csv: one row per image; the last two from the registrations' true overlaps
/// (replay/proposal_recall.h; 0 in a dive without them).
struct ProposalsCsv {
  enum Index : std::size_t {
    kFrameId,
    kCandidates,
    kProposed,
    kAccepted,
    kTrueOverlapping,          ///< true_overlapping: earlier images overlapping >= 20 %
    kTrueOverlappingProposed,  ///< true_overlapping_proposed: of them proposed
    kCount
  };
  static const CsvSchema& schema();
};

/// published.csv: the robot's solution as navd publishes it (dive_replay.h PublishedSolution):
/// t_us, the pose, and the upper triangle c<r><c> (r <= c) of its 6x6 covariance, row-major.
struct PublishedCsv {
  enum Index : std::size_t { kTimeUs, kPose, kCovariance = kPose + 6, kCount = kCovariance + 21 };
  /// Index of covariance cell (row, col), row <= col.
  static constexpr std::size_t cell(int row, int col) {
    return kCovariance + static_cast<std::size_t>(row * 6 - row * (row - 1) / 2 + (col - row));
  }
  static const CsvSchema& schema();
};

/// information_blocks.csv: a comment line "# block_dim D num_blocks N", the header row, then
/// one row per non-zero block (i <= j) of the final information matrix.
struct InformationBlocksCsv {
  enum Index : std::size_t { kI, kJ, kCount };
  /// The comment's keys, in order: "# <kBlockDimKey> D <kNumBlocksKey> N".
  static constexpr std::string_view kBlockDimKey = "block_dim";
  static constexpr std::string_view kNumBlocksKey = "num_blocks";
  /// The comment line (with '#', without newline).
  static std::string comment(int block_dim, int num_blocks);
  static const CsvSchema& schema();
};

/// logdet.csv: log(det approx / det exact) of relative-pose covariances (Fig. 3).
struct LogdetCsv {
  enum Index : std::size_t { kStateI, kStateJ, kOurs, kMarkovBlanket, kCount };
  static const CsvSchema& schema();
};

/// time_of_use.csv: Fig. 3's log-det ratios at the time of use (core/recovery/time_of_use.h),
/// one row per (check, state): the frame id of the image checked (before its link proposal),
/// the delayed state i, ours and the Markov blanket's (empty when not computed).
struct TimeOfUseCsv {
  enum Index : std::size_t { kFrameId, kState, kOurs, kMarkovBlanket, kCount };
  static const CsvSchema& schema();
};

}  // namespace nav::daemon::output_schema
