#pragma once
#include <string>

#include "drivers/csv/csv_table.h"

namespace canalid::cli {

/// The record a report is made from, as an in-memory table (time_s first, named columns,
/// uniform sampling).  Today a CSV file (DESIGN.md's CSV interface); a log converted to
/// per-reach tables (drivers::CsvTable::FromColumns) enters the report here as well.
/// @throws InputError naming the file, line and column of a bad CSV.
drivers::CsvTable LoadReportInput(const std::string& path);

}  // namespace canalid::cli
