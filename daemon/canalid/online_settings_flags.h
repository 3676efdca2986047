#pragma once
// The settings every estimator of `canalid identify --online` shares, from the command's flags.
#include "core/online/online_model.h"
#include "daemon/canalid/identify_command.h"
#include "drivers/csv/csv_table.h"

namespace canalid::cli {

/// Settings with the record's sample time, --method, --forgetting and --initial-covariance (none:
/// each kind's default, as in the daemon's configuration); the rest at OnlineModelSettings'
/// defaults.
/// @throws InputError naming the flag: an unknown method, a forgetting outside (0, 1], a P0
/// outside (0, 1e20].
core::OnlineModelSettings OnlineSettingsFromFlags(const IdentifyOptions& options,
                                                  const drivers::CsvTable& table);

}  // namespace canalid::cli
