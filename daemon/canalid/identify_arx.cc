#include <new>
#include <stdexcept>
#include <utility>

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
  const auto y = RequireColumn(table, options.y);
  const Eigen::Index rows = table.rows();
  data.preprocessing = {{"detrended", options.detrend}};
  if (options.detrend) {
    core::DetrendResult line = core::RemoveLinearTrend(y);
    data.y_copy_ = std::move(line.detrended);
    new (&data.y) Eigen::Map<const Eigen::VectorXd>(data.y_copy_.data(), rows);
    data.preprocessing["y_trend"] = {{"intercept", line.intercept},
                                     {"slope_per_sample", line.slope_per_sample}};
  } else {
    new (&data.y) Eigen::Map<const Eigen::VectorXd>(y.data(), rows);
  }
  if (m == 1 && !options.detrend) {
    const auto u = RequireMovingColumn(table, data.inputs.front());
    new (&data.u) Eigen::Map<const Eigen::MatrixXd>(u.data(), rows, 1);
    return data;
  }
  data.u_copy_.resize(rows, static_cast<Eigen::Index>(m));
  for (std::size_t i = 0; i < m; ++i) {
    const auto u = RequireMovingColumn(table, data.inputs[i]);
    data.u_copy_.col(static_cast<Eigen::Index>(i)) =
        options.detrend ? core::RemoveLinearTrend(u).detrended : u;
  }
  new (&data.u)
      Eigen::Map<const Eigen::MatrixXd>(data.u_copy_.data(), rows, static_cast<Eigen::Index>(m));
  return data;
}

nlohmann::json IdentifyArx(const IdentifyOptions& options, const drivers::CsvTable& table) {
  const ArxData data = ReadArxData(options, table);
  const std::vector<std::string>& inputs = data.inputs;
  const core::ArxOrders& orders = data.orders;
  const auto& y = data.y;
  const auto& u = data.u;
  const nlohmann::json& preprocessing = data.preprocessing;
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
