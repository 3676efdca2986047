#pragma once
#include <string>
#include <vector>

#include "daemon/canalid/identify_command.h"

namespace CLI {
class App;
}

namespace canalid::cli {

/// Everything `canalid report` takes from the command line.
struct ReportOptions {
  std::string input;                ///< CSV record or LCM log (LoadReportInput)
  std::string reach;                ///< log input: the reach
  std::string config;               ///< log input: configuration instead of the log's
  std::vector<std::string> models;  ///< kinds, identified in this order
  std::string out;                  ///< directory for index.html, the images and gnuplot/
  std::string gnuplot = "gnuplot";  ///< program that draws the plots
  IdentifyOptions identify;         ///< columns and settings, as `identify` takes them
};

/// Registers `report` on the app; `exit_code` receives the result when it runs.
void AddReportCommand(CLI::App& app, ReportOptions& options, int& exit_code);

/// Identifies every kind on the record, simulates, plots with gnuplot and writes
/// out/index.html.  Returns 0, or 1 (after printing why) when gnuplot is missing or fails.
/// @throws InputError on bad input (the CSV, columns, options).
int RunReport(const ReportOptions& options, const std::string& command_line);

}  // namespace canalid::cli
