#pragma once
#include <array>
#include <optional>
#include <string>

#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/report_online.h"
#include "drivers/csv/csv_table.h"

namespace canalid::cli {

/// Where a report's record comes from when --input is an LCM log of canalidd.
struct ReportLogOptions {
  std::string reach;     ///< the reach to report on; empty: the log's only one
  std::string config;    ///< daemon configuration instead of the one in the log
  std::string data_dir;  ///< where the reach's samples are exported (DIR/data of the report)
};

/// The record a report is made from.
struct ReportInput {
  drivers::CsvTable table;
  /// For a log: the reach's channel names (inflow, outflow, level, actuator), the columns of
  /// `table`, used as identify's defaults (id: q_in, q_out, level; others: u = actuator,
  /// y = level).
  std::optional<std::array<std::string, 4>> reach_channels;
  /// For a log: the reach's online models as the daemon published them.
  std::vector<OnlineTrajectory> online;
};

/// The record of a report as an in-memory table (time_s first, named columns, uniform sampling):
/// a CSV file (docs/design.md's CSV interface), or an LCM log of canalidd (recognised by the LCM
/// event sync word), whose reach is exported as `canalid export` does into
/// `log.data_dir/<reach>.csv` and read from there.
/// @throws InputError naming the file, line and column of a bad CSV, a damaged log (byte offset),
///         or a reach that is missing or not unique.
ReportInput LoadReportInput(const std::string& path, const ReportLogOptions& log = {});

/// Identify's options with the reach's channels as the column defaults, where the command line
/// left them at their defaults.
IdentifyOptions WithReachColumns(IdentifyOptions options,
                                 const std::array<std::string, 4>& channels);

/// True when the file begins with an LCM event (big-endian 0xEDA1DA01).
bool IsLcmLog(const std::string& path);

}  // namespace canalid::cli
