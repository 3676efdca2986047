#pragma once
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/report_analysis.h"
#include "drivers/csv/csv_table.h"

namespace canalid::cli {

/// With --canal and --pool: adds to an idz model's analysis the step response of the IDZ model the
/// pool's geometry gives (canalid theory, at the record's mean inflow), y(t) = (t - tau)/A + p21
/// after the delay, and the frequency responses p21(jw) of both models, identified and theory,
/// from 0.01/tau to min(100/tau, pi/Ts).  Nothing without --canal.
/// @throws InputError as PoolTheory.
void AddIdzTheory(ModelAnalysis& idz, const IdentifyOptions& options,
                  const drivers::CsvTable& table);

}  // namespace canalid::cli
