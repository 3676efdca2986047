#include <stdexcept>

#include "core/integrator_delay/identify_integrator_delay.h"
#include "daemon/canalid/closed_loop_option.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {

nlohmann::json IdentifyId(const IdentifyOptions& options, const drivers::CsvTable& table) {
  const core::ClosedLoopMode closed_loop = ParseClosedLoop(options.closed_loop);
  if (closed_loop == core::ClosedLoopMode::kOn) {
    throw InputError(
        "--closed-loop iv: the instrumental-variable bank is --online only (the batch fit reports "
        "its IV estimate under cross_check)");
  }
  const auto q_in = RequireMovingColumn(table, options.qin);
  const auto q_out = RequireColumn(table, options.qout);
  const auto level = RequireColumn(table, options.level);
  const double ts = table.sample_time_s();
  core::IntegratorDelayIdentificationOptions pipeline;
  pipeline.remove_level_outliers = !options.keep_outliers;
  pipeline.fit.closed_loop = closed_loop;
  if (options.max_delay_s > 0.0) {
    pipeline.fit.max_nk = OptionSamples(options.max_delay_s, table, "--max-delay-s", false);
  }
  try {
    return drivers::ToJson(core::IdentifyIntegratorDelay(q_in, q_out, level, ts, pipeline));
  } catch (const std::invalid_argument& e) {
    throw InputError(table.source() + ": " + e.what());
  }
}

}  // namespace canalid::cli
