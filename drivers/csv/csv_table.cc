#include "drivers/csv/csv_table.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <unordered_set>

namespace canalid::drivers {
namespace {

std::string Trim(std::string_view s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return {};
  const auto end = s.find_last_not_of(" \t\r");
  return std::string(s.substr(begin, end - begin + 1));
}

std::vector<std::string> SplitCells(const std::string& line) {
  std::vector<std::string> cells;
  std::string_view rest(line);
  while (true) {
    const auto comma = rest.find(',');
    cells.push_back(Trim(rest.substr(0, comma)));
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  return cells;
}

[[noreturn]] void Fail(const std::string& source, std::size_t line, const std::string& what) {
  throw CsvError(source + ":" + std::to_string(line) + ": " + what);
}

std::string CellText(double v) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, end);
}

// What is wrong with a header (empty when nothing): time_s first, every name present and unique.
std::string HeaderProblem(const std::vector<std::string>& columns) {
  if (columns.empty() || columns.front() != "time_s") {
    return "the first column must be 'time_s' (found '" +
           (columns.empty() ? std::string() : columns.front()) + "')";
  }
  std::unordered_set<std::string> seen;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    if (columns[c].empty()) return "column " + std::to_string(c + 1) + " has no name";
    if (!seen.insert(columns[c]).second) return "column '" + columns[c] + "' appears twice";
  }
  return {};
}

// What is wrong with time t of row `rows` (1-based, >= 2) after t_prev, the first time being t0
// (empty when nothing).  Row 2 sets the sample time.
std::string TimeProblem(double t0, double t_prev, double t, std::size_t rows,
                        double& sample_time_s) {
  if (!(t > t_prev)) {
    return "time_s " + CellText(t) + " does not increase (previous " + CellText(t_prev) + ")";
  }
  if (rows == 2) {
    sample_time_s = t - t_prev;
    return {};
  }
  const double expected = t0 + static_cast<double>(rows - 1) * sample_time_s;
  if (std::abs(t - expected) > 1e-6 * sample_time_s * static_cast<double>(rows) + 1e-9) {
    return "time_s " + CellText(t) + " breaks uniform sampling (expected " + CellText(expected) +
           ", sample time " + CellText(sample_time_s) + " s)";
  }
  return {};
}

}  // namespace

bool CsvTable::HasColumn(const std::string& name) const {
  for (const auto& c : columns_) {
    if (c == name) return true;
  }
  return false;
}

Eigen::VectorXd CsvTable::Column(const std::string& name) const {
  for (std::size_t i = 0; i < columns_.size(); ++i) {
    if (columns_[i] == name) return data_.col(static_cast<Eigen::Index>(i));
  }
  std::string known;
  for (const auto& c : columns_) known += (known.empty() ? "" : ", ") + c;
  throw CsvError(source_ + ": no column '" + name + "' (columns: " + known + ")");
}

CsvTable CsvTable::Read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw CsvError(path + ": cannot open file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return Parse(buffer.str(), path);
}

CsvTable CsvTable::Parse(const std::string& text, const std::string& name) {
  CsvTable table;
  table.source_ = name;
  std::istringstream in(text);
  std::string line;
  std::size_t line_number = 0;
  // Header: the first line that is not blank.
  while (std::getline(in, line)) {
    ++line_number;
    if (!Trim(line).empty()) break;
  }
  if (Trim(line).empty()) throw CsvError(name + ": empty file (no header row)");
  table.columns_ = SplitCells(line);
  if (const std::string problem = HeaderProblem(table.columns_); !problem.empty()) {
    Fail(name, line_number, problem);
  }
  const std::size_t width = table.columns_.size();
  std::vector<double> values;
  std::size_t rows = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (Trim(line).empty()) continue;
    const auto cells = SplitCells(line);
    if (cells.size() != width) {
      Fail(name, line_number,
           "expected " + std::to_string(width) + " cells, found " + std::to_string(cells.size()));
    }
    for (std::size_t c = 0; c < width; ++c) {
      double v = 0.0;
      const auto& cell = cells[c];
      const auto [ptr, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), v);
      if (cell.empty() || ec != std::errc() || ptr != cell.data() + cell.size()) {
        Fail(name, line_number,
             "column '" + table.columns_[c] + "': '" + cell + "' is not a number");
      }
      if (!std::isfinite(v)) {
        Fail(name, line_number, "column '" + table.columns_[c] + "': '" + cell + "' is not finite");
      }
      values.push_back(v);
    }
    ++rows;
    // Time checks as rows arrive, so the message names the offending line.
    const std::size_t base = (rows - 1) * width;
    if (rows >= 2) {
      const std::string problem =
          TimeProblem(values[0], values[base - width], values[base], rows, table.sample_time_s_);
      if (!problem.empty()) Fail(name, line_number, problem);
    }
  }
  if (rows < 2)
    throw CsvError(name + ": needs at least 2 data rows, found " + std::to_string(rows));
  table.data_ =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          values.data(), static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(width));
  return table;
}

CsvTable CsvTable::FromColumns(const std::string& source, const std::vector<std::string>& names,
                               const std::vector<Eigen::VectorXd>& columns) {
  if (const std::string problem = HeaderProblem(names); !problem.empty()) {
    throw CsvError(source + ": " + problem);
  }
  if (columns.size() != names.size()) {
    throw CsvError(source + ": " + std::to_string(names.size()) + " names but " +
                   std::to_string(columns.size()) + " columns");
  }
  const Eigen::Index rows = columns.front().size();
  if (rows < 2) throw CsvError(source + ": needs at least 2 rows, found " + std::to_string(rows));
  CsvTable table;
  table.source_ = source;
  table.columns_ = names;
  table.data_.resize(rows, static_cast<Eigen::Index>(names.size()));
  for (std::size_t c = 0; c < names.size(); ++c) {
    if (columns[c].size() != rows) {
      throw CsvError(source + ": column '" + names[c] + "' has " +
                     std::to_string(columns[c].size()) + " rows, time_s has " +
                     std::to_string(rows));
    }
    for (Eigen::Index r = 0; r < rows; ++r) {
      if (!std::isfinite(columns[c](r))) {
        throw CsvError(source + ": row " + std::to_string(r + 1) + ": column '" + names[c] +
                       "' is not finite");
      }
    }
    table.data_.col(static_cast<Eigen::Index>(c)) = columns[c];
  }
  const Eigen::VectorXd& t = columns.front();
  for (Eigen::Index r = 1; r < rows; ++r) {
    const std::string problem =
        TimeProblem(t(0), t(r - 1), t(r), static_cast<std::size_t>(r + 1), table.sample_time_s_);
    if (!problem.empty()) {
      std::string message = source + ": row " + std::to_string(r + 1) + ": ";
      message += problem;
      throw CsvError(message);
    }
  }
  return table;
}

void WriteCsv(const std::string& path, const std::vector<std::string>& names,
              const std::vector<Eigen::VectorXd>& columns) {
  if (names.size() != columns.size() || columns.empty()) {
    throw CsvError(path + ": WriteCsv needs one name per column");
  }
  const Eigen::Index n = columns.front().size();
  for (const auto& c : columns) {
    if (c.size() != n) throw CsvError(path + ": WriteCsv columns differ in length");
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw CsvError(path + ": cannot open for writing");
  for (std::size_t c = 0; c < names.size(); ++c) out << (c ? "," : "") << names[c];
  out << "\n";
  char buffer[32];
  for (Eigen::Index r = 0; r < n; ++r) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, columns[c](r));
      if (c) out << ',';
      out.write(buffer, end - buffer);
    }
    out << '\n';
  }
  if (!out.flush()) throw CsvError(path + ": write failed");
}

}  // namespace canalid::drivers
