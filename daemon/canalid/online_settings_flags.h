#pragma once
// The settings every estimator of `canalid identify --online` shares, from the command's flags.
#include "core/online/online_model.h"
#include "daemon/canalid/identify_command.h"
#include "drivers/csv/csv_table.h"

namespace canalid::cli {

/// Settings with the record's sample time, --method, --forgetting and the initial covariance of
/// the command (1e10 I: with forgetting 1 the estimates are the batch least-squares ones, the
/// prior's weight ||theta||^2 / P0 being negligible against the data's information; the daemon
/// keeps RlsOptions' 1e6, which --config gives).  The rest at OnlineModelSettings' defaults.
/// @throws InputError naming the flag: an unknown method, a forgetting outside (0, 1].
core::OnlineModelSettings OnlineSettingsFromFlags(const IdentifyOptions& options,
                                                  const drivers::CsvTable& table);

}  // namespace canalid::cli
