#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "daemon/canalid/report_analysis.h"
#include "daemon/canalid/report_plots.h"
#include "drivers/csv/csv_table.h"

namespace canalid::cli {

/// Numbers in the report's tables: 6 significant digits (printf "%.6g").
std::string ReportNumber(double value);

/// The model table's cells for one model JSON: fit %, RMSE, MAE, normalised error, delay (s) and
/// area (m2, ID models) when the model has them, and the other parameters as "name = value".
struct ModelRow {
  std::vector<std::pair<std::string, std::string>> metrics;  ///< (class, text), fixed order
  std::string parameters;
};
ModelRow ModelTableRow(const nlohmann::json& model);

/// Writes the self-contained page (no scripts, no network; images by relative link): the record,
/// the table of models and metrics, every plot by section with the notes, and each model's JSON.
/// @throws ToolError if the file cannot be written.
void WriteReportHtml(const std::filesystem::path& path, const drivers::CsvTable& table,
                     const std::string& command_line, const std::vector<ModelAnalysis>& models,
                     const std::vector<Plot>& plots);

}  // namespace canalid::cli
