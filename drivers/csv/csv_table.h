#pragma once
#include <Eigen/Core>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/system/large_buffer.h"

namespace canalid::drivers {

/// A bad CSV file: the message names the file, the line (1-based, the header is line 1) and the
/// column where they apply, e.g. "data.csv:14: column 'level': 'abc' is not a number".
class CsvError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A uniformly sampled table read from CSV (docs/design.md): a header row of column names, `time_s`
/// first, then one numeric row per sample.  Rejected, with file, line and column: a missing file,
/// an empty file, a header without `time_s` first, duplicate names, rows with the wrong number
/// of cells, a cell that is not a finite number, time that does not increase, sampling that is
/// not uniform (relative tolerance 1e-6 of the first interval; gaps are never resampled), and
/// fewer than 2 rows.
class CsvTable {
 public:
  /// The bytes Read reads at a time: the buffer it reuses for the whole file.
  static constexpr std::size_t kReadChunkBytes = std::size_t{64} * 1024;
  /// Reads a file or a pipe, a chunk at a time, parsing each whole line where it lies.
  /// @throws CsvError
  static CsvTable Read(const std::string& path);
  /// Read with another chunk size (for tests: lines across chunks, lines longer than a chunk).
  static CsvTable Read(const std::string& path, std::size_t chunk_bytes);
  /// Parses text as if it were the contents of a file called `name` (for tests), in place: no
  /// copies of lines or cells.
  /// @throws CsvError
  static CsvTable Parse(std::string_view text, const std::string& name);
  /// A table from columns in memory (e.g. decoded from a log), checked as Read checks a file;
  /// messages name `source` and the row (1-based, data rows only).  columns[0] is time_s.
  /// @throws CsvError
  static CsvTable FromColumns(const std::string& source, const std::vector<std::string>& names,
                              const std::vector<Eigen::VectorXd>& columns);

  const std::string& source() const { return source_; }
  const std::vector<std::string>& columns() const { return columns_; }
  Eigen::Index rows() const { return rows_; }
  double sample_time_s() const { return sample_time_s_; }
  /// A column of the table: a view of the table's own values, valid while the table lives (copy
  /// it into an Eigen::VectorXd to keep it longer).
  using ColumnView = Eigen::Map<const Eigen::VectorXd>;
  ColumnView time_s() const& { return View(0); }
  /// From a temporary table, a copy: a view would outlive it.
  Eigen::VectorXd time_s() && { return View(0); }
  bool HasColumn(const std::string& name) const;
  /// @throws CsvError naming the file, the missing column and the columns there are.
  ColumnView Column(const std::string& name) const& { return View(ColumnIndex(name)); }
  Eigen::VectorXd Column(const std::string& name) && { return View(ColumnIndex(name)); }

 private:
  CsvTable(std::string source, std::vector<std::string> columns, core::LargeBuffer values,
           Eigen::Index stride, Eigen::Index rows, double sample_time_s);
  /// @throws CsvError as Column does.
  std::size_t ColumnIndex(const std::string& name) const;
  ColumnView View(std::size_t column) const {
    return {values_.data() + static_cast<Eigen::Index>(column) * stride_, rows_};
  }

  std::string source_;
  std::vector<std::string> columns_;
  // A column per column, in one block, column c from values_.data() + c * stride_; its first
  // rows_ rows are the table's (the reader may leave room after them).
  core::LargeBuffer values_;
  Eigen::Index stride_ = 0;
  Eigen::Index rows_ = 0;
  double sample_time_s_ = 0.0;
};

/// Writes `time_s` and the given columns as CSV with full double precision (17 significant
/// digits).  @throws CsvError if the file cannot be written or the sizes disagree.
void WriteCsv(const std::string& path, const std::vector<std::string>& names,
              const std::vector<Eigen::VectorXd>& columns);

}  // namespace canalid::drivers
