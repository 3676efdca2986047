#include "daemon/canalid/table_columns.h"

#include <charconv>
#include <cmath>

#include "daemon/canalid/input_error.h"

namespace canalid::cli {

drivers::CsvTable ReadTable(const std::string& path) {
  try {
    return drivers::CsvTable::Read(path);
  } catch (const drivers::CsvError& e) {
    throw InputError(e.what());
  }
}

drivers::CsvTable::ColumnView RequireColumn(const drivers::CsvTable& table,
                                            const std::string& name) {
  try {
    return table.Column(name);
  } catch (const drivers::CsvError& e) {
    throw InputError(e.what());
  }
}

drivers::CsvTable::ColumnView RequireMovingColumn(const drivers::CsvTable& table,
                                                  const std::string& name) {
  const drivers::CsvTable::ColumnView column = RequireColumn(table, name);
  if (column.maxCoeff() == column.minCoeff()) {
    throw InputError(table.source() + ": column '" + name + "' never moves (constant " +
                     std::to_string(column(0)) + " over " + std::to_string(column.size()) +
                     " rows), so it cannot excite the model");
  }
  return column;
}

namespace {

[[noreturn]] void ThrowEmptyItem(const std::string& option, const std::string& text) {
  throw InputError(option + ": empty item in '" + text + "'");
}

[[noreturn]] void ThrowNotWholeNumber(const std::string& option, const std::string& part) {
  throw InputError(option + ": '" + part + "' is not a whole number >= 0");
}

[[noreturn]] void ThrowNonFiniteOutput(const std::string& what, double value, Eigen::Index row,
                                       const drivers::CsvTable& table) {
  const std::string time =
      row < table.rows() ? " (time_s " + std::to_string(table.time_s()(row)) + ")" : "";
  throw InputError(what + ": the simulated output is " + std::to_string(value) + " from row " +
                   std::to_string(row) + time + " of " + table.source() +
                   " (an unstable or overflowing model on this record); nothing written");
}

}  // namespace

std::vector<std::string> SplitList(const std::string& text, const std::string& option) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (part.empty()) ThrowEmptyItem(option, text);
    parts.push_back(part);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return parts;
}

std::vector<int> ParseIntList(const std::string& text, const std::string& option) {
  std::vector<int> values;
  for (const auto& part : SplitList(text, option)) {
    int v = 0;
    const auto [ptr, ec] = std::from_chars(part.data(), part.data() + part.size(), v);
    if (ec != std::errc() || ptr != part.data() + part.size() || v < 0) {
      ThrowNotWholeNumber(option, part);
    }
    values.push_back(v);
  }
  return values;
}

void RequireFiniteOutput(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Index first_row,
                         const drivers::CsvTable& table, const std::string& what) {
  for (Eigen::Index k = 0; k < y.size(); ++k) {
    if (!std::isfinite(y(k))) ThrowNonFiniteOutput(what, y(k), first_row + k, table);
  }
}

int OptionSamples(double seconds, const drivers::CsvTable& table, const std::string& option,
                  bool nearest) {
  const double samples = seconds / table.sample_time_s();
  const double whole = nearest ? std::round(samples) : std::floor(samples);
  if (!(whole >= 0.0 && whole < static_cast<double>(table.rows()))) {
    throw InputError(option + " " + std::to_string(seconds) + " s is " + std::to_string(samples) +
                     " samples of " + std::to_string(table.sample_time_s()) + " s; " +
                     table.source() + " has " + std::to_string(table.rows()) +
                     " rows (allowed: fewer samples than rows)");
  }
  return static_cast<int>(whole);
}

}  // namespace canalid::cli
