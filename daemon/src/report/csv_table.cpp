// CsvTable: see csv_table.h.
#include "nav/report/csv_table.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

namespace nav::report {
namespace {

std::vector<std::string> split_fields(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    std::string field = line.substr(start, comma == std::string::npos ? comma : comma - start);
    // Tolerate surrounding blanks (hand-written fixtures, "a, b").
    const size_t first = field.find_first_not_of(" \t");
    const size_t last = field.find_last_not_of(" \t");
    fields.push_back(first == std::string::npos ? std::string()
                                                : field.substr(first, last - first + 1));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return fields;
}

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (size_t i = 0; i < v.size(); ++i) out += (i ? "," : "") + v[i];
  return out;
}

}  // namespace

CsvTable CsvTable::read(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ReportError(path.string() + ": cannot open");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse(ss.str(), path.string());
}

CsvTable CsvTable::parse(const std::string& text, const std::string& name) {
  CsvTable t;
  t.name_ = name;
  std::istringstream in(text);
  int line_no = 0;
  for (std::string line; std::getline(in, line);) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    if (line[0] == '#') {
      t.comments_.push_back(line.substr(1));
      continue;
    }
    std::vector<std::string> fields = split_fields(line);
    if (t.header_.empty()) {
      t.header_ = std::move(fields);
      continue;
    }
    if (fields.size() != t.header_.size()) {
      throw ReportError(name + ":" + std::to_string(line_no) + ": " +
                        std::to_string(fields.size()) + " fields, header has " +
                        std::to_string(t.header_.size()));
    }
    t.cells_.push_back(std::move(fields));
    t.lines_.push_back(line_no);
  }
  if (t.header_.empty()) throw ReportError(name + ": empty file (no header line)");
  return t;
}

std::optional<size_t> CsvTable::find_column(const std::string& column) const {
  for (size_t i = 0; i < header_.size(); ++i) {
    if (header_[i] == column) return i;
  }
  return std::nullopt;
}

size_t CsvTable::column(const std::string& column) const {
  if (auto i = find_column(column)) return *i;
  throw ReportError(name_ + ": missing column '" + column + "' (header: " + join(header_) + ")");
}

std::string CsvTable::where(size_t row) const { return name_ + ":" + std::to_string(lines_[row]); }

void CsvTable::bad_cell(size_t row, size_t col, const char* what) const {
  throw ReportError(where(row) + ": column '" + header_[col] + "': '" + cells_[row][col] +
                    "' is not " + what);
}

double CsvTable::number(size_t row, size_t col) const {
  const std::string& s = cells_[row][col];
  double value = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(value)) {
    bad_cell(row, col, "a finite number");
  }
  return value;
}

long long CsvTable::integer(size_t row, size_t col) const {
  const std::string& s = cells_[row][col];
  long long value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (s.empty() || ec != std::errc() || end != s.data() + s.size()) {
    bad_cell(row, col, "an integer");
  }
  return value;
}

bool CsvTable::boolean(size_t row, size_t col) const {
  const std::string& s = cells_[row][col];
  if (s == "1" || s == "true") return true;
  if (s == "0" || s == "false") return false;
  bad_cell(row, col, "a boolean (0/1/true/false)");
}

}  // namespace nav::report
