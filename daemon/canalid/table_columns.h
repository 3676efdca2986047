#pragma once
#include <Eigen/Core>
#include <string>
#include <vector>

#include "drivers/csv/csv_table.h"

namespace canalid::cli {

/// A column that must carry information: present, and (for inputs) not constant.
/// @throws InputError naming the file, the column and the problem.
Eigen::VectorXd RequireColumn(const drivers::CsvTable& table, const std::string& name);
Eigen::VectorXd RequireMovingColumn(const drivers::CsvTable& table, const std::string& name);

/// Splits "a,b,c" into its non-empty parts.  @throws InputError on an empty part.
std::vector<std::string> SplitList(const std::string& text, const std::string& option);
std::vector<int> ParseIntList(const std::string& text, const std::string& option);

}  // namespace canalid::cli
