#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "drivers/csv/csv_table.h"

namespace canalid::cli {

/// A CSV record (drivers::CsvTable::Read).  @throws InputError with the reader's message (file,
/// line, column).
drivers::CsvTable ReadTable(const std::string& path);

/// A column that must carry information: present, and (for inputs) not constant.  The table's
/// own column (a view): copy it to keep it past the table.
/// @throws InputError naming the file, the column and the problem.
drivers::CsvTable::ColumnView RequireColumn(const drivers::CsvTable& table,
                                            const std::string& name);
drivers::CsvTable::ColumnView RequireMovingColumn(const drivers::CsvTable& table,
                                                  const std::string& name);

/// Splits "a,b,c" into its non-empty parts.  @throws InputError on an empty part.
std::vector<std::string> SplitList(const std::string& text, const std::string& option);
std::vector<int> ParseIntList(const std::string& text, const std::string& option);

/// A simulated output must be finite before anything is written from it: @throws InputError
/// naming `what` (file and model), the first row (of the table: first_row + index) where a
/// non-finite value appeared, its time and the value.
void RequireFiniteOutput(const Eigen::Ref<const Eigen::VectorXd>& y, Eigen::Index first_row,
                         const drivers::CsvTable& table, const std::string& what);

/// A duration option in whole samples of the table (seconds / Ts, rounded to the nearest with
/// `nearest`, else down): checked before the conversion to be less than the record's rows, so
/// that no int overflows and no delay outruns the data.  @throws InputError naming the option,
/// the value in seconds and samples, and the record.
int OptionSamples(double seconds, const drivers::CsvTable& table, const std::string& option,
                  bool nearest);

}  // namespace canalid::cli
