#pragma once
// A CSV file with a header row, read whole, with errors that name file:line and the column.
// The replay-output and dive-directory formats (hil-tests/README.md) are plain comma-separated
// tables without quoting; lines starting with '#' are comments (information_blocks.csv starts
// with one) and blank lines are skipped.

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace nav::report {

/// Bad input file: the message names the file (and line and column when it applies).
struct ReportError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class CsvTable {
 public:
  /// Reads `path`. The first non-comment line is the header. Every data row must have as many
  /// fields as the header ("file:line: 5 fields, header has 8"). Throws ReportError when the file
  /// cannot be opened or has no header.
  static CsvTable read(const std::filesystem::path& path);
  /// Parses `text` as if it were the content of a file called `name` (tests, in-memory use).
  static CsvTable parse(const std::string& text, const std::string& name);

  const std::string& name() const { return name_; }
  const std::vector<std::string>& header() const { return header_; }
  size_t rows() const { return cells_.size(); }
  /// Comment lines ('#...') in file order, without the '#'.
  const std::vector<std::string>& comments() const { return comments_; }

  /// Column index of `column`; ReportError "file: missing column 'x' (header: a,b,c)".
  size_t column(const std::string& column) const;
  /// Column index of `column`, or nothing when the header does not have it.
  std::optional<size_t> find_column(const std::string& column) const;

  /// The raw text of a cell.
  const std::string& text(size_t row, size_t col) const { return cells_[row][col]; }
  /// The cell as a finite double; ReportError "file:line: column 'x': 'abc' is not a number".
  double number(size_t row, size_t col) const;
  /// The cell as a whole number (no fraction, fits in int64); same error style.
  long long integer(size_t row, size_t col) const;
  /// The cell as a boolean: 1/0/true/false; same error style.
  bool boolean(size_t row, size_t col) const;
  /// The line number (1-based) in the file of a data row, for messages.
  int line(size_t row) const { return lines_[row]; }
  /// "file:line" of a data row.
  std::string where(size_t row) const;

 private:
  [[noreturn]] void bad_cell(size_t row, size_t col, const char* what) const;

  std::string name_;
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> cells_;
  std::vector<int> lines_;
  std::vector<std::string> comments_;
};

}  // namespace nav::report
