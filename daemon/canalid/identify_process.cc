#include <stdexcept>

#include "core/linear/process_model_fit.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {

nlohmann::json IdentifyProcessModel(const IdentifyOptions& options,
                                    const drivers::CsvTable& table) {
  const Eigen::VectorXd u = RequireMovingColumn(table, options.u);
  const Eigen::VectorXd y = RequireColumn(table, options.y);
  try {
    if (options.model == "foptd")
      return drivers::ToJson(core::FitFoptd(u, y, table.sample_time_s()));
    return drivers::ToJson(core::FitSoptd(u, y, table.sample_time_s()));
  } catch (const std::invalid_argument& e) {
    throw InputError(table.source() + ": " + e.what());
  }
}

}  // namespace canalid::cli
