#include <stdexcept>

#include "core/linear/arx.h"
#include "core/numerics/metrics.h"
#include "core/signal/detrend.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {

ArxData ReadArxData(const IdentifyOptions& options, const drivers::CsvTable& table) {
  ArxData data;
  data.inputs = SplitList(options.u, "--u");
  const std::size_t m = data.inputs.size();
  core::ArxOrders& orders = data.orders;
  orders.na = options.na;
  orders.nb = ParseIntList(options.nb, "--nb");
  orders.nk = ParseIntList(options.nk, "--nk");
  // One value of nb or nk applies to every input, as in MATLAB's arx.
  if (orders.nb.size() == 1) orders.nb.resize(m, orders.nb.front());
  if (orders.nk.size() == 1) orders.nk.resize(m, orders.nk.front());
  if (orders.nb.size() != m || orders.nk.size() != m) {
    throw InputError("--nb and --nk need one value, or one per input column (" + std::to_string(m) +
                     ")");
  }
  try {
    orders.Validate(static_cast<Eigen::Index>(m));
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  data.y = RequireColumn(table, options.y);
  data.u.resize(table.rows(), static_cast<Eigen::Index>(m));
  for (std::size_t i = 0; i < m; ++i) {
    data.u.col(static_cast<Eigen::Index>(i)) = RequireMovingColumn(table, data.inputs[i]);
  }
  data.preprocessing = {{"detrended", options.detrend}};
  if (options.detrend) {
    const core::DetrendResult line = core::RemoveLinearTrend(data.y);
    data.y = line.detrended;
    data.preprocessing["y_trend"] = {{"intercept", line.intercept},
                                     {"slope_per_sample", line.slope_per_sample}};
    for (Eigen::Index i = 0; i < data.u.cols(); ++i) {
      data.u.col(i) = core::RemoveLinearTrend(data.u.col(i)).detrended;
    }
  }
  return data;
}

nlohmann::json IdentifyArx(const IdentifyOptions& options, const drivers::CsvTable& table) {
  const ArxData data = ReadArxData(options, table);
  const auto& [inputs, orders, y, u, preprocessing] = data;
  try {
    const core::ArxModel model = core::FitArx(y, u, orders);
    nlohmann::json json = drivers::ToJson(model);
    json["inputs"] = inputs;
    json["output"] = options.y;
    json["sample_time_s"] = table.sample_time_s();
    json["preprocessing"] = preprocessing;
    // Validation by simulation from the first measured outputs, not one-step prediction.
    const Eigen::Index warmup = std::max<Eigen::Index>(model.first_sample, 1);
    const Eigen::VectorXd simulated = core::SimulateArx(model, u, y.head(warmup));
    RequireFiniteOutput(simulated.tail(y.size() - warmup), warmup, table, "--model arx (fitted)");
    json["metrics"] = drivers::ToJson(core::ComputeMetrics(
        y.tail(y.size() - warmup), simulated.tail(y.size() - warmup), table.sample_time_s()));
    return json;
  } catch (const std::invalid_argument& e) {
    throw InputError(table.source() + ": " + e.what());
  }
}

}  // namespace canalid::cli
