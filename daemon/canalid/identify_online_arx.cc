// `canalid identify --model arx --online` with the flags: one recursive estimator over the ARX rows
// of a CSV record (any number of inputs, each with its nb and nk), printed in the batch arx keys
// plus `estimator` and `health`.  The estimator is an Rls<n> of the record's parameter count where
// n <= 8 (fixed-size Eigen, no allocation per row), else Rls<Dynamic>.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/linear/arx.h"
#include "core/numerics/metrics.h"
#include "core/online/online_model.h"
#include "core/online/rls.h"
#include "core/system/large_buffer.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/online_settings_flags.h"
#include "daemon/canalid/rls_health_json.h"
#include "daemon/canalid/trace_writer.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {
namespace {

// Row t of core::ArxRegressors: [-y(t-1)..-y(t-na), u_i(t-nk_i)..u_i(t-nk_i-nb_i+1)].
template <class Phi>
void FillRow(const ArxData& data, Eigen::Index t, Phi& phi) {
  const core::ArxOrders& orders = data.orders;
  Eigen::Index c = 0;
  for (int j = 1; j <= orders.na; ++j) phi(c++) = -data.y(t - j);
  for (std::size_t i = 0; i < data.inputs.size(); ++i) {
    const auto col = static_cast<Eigen::Index>(i);
    for (int j = 0; j < orders.nb[i]; ++j) phi(c++) = data.u(t - orders.nk[i] - j, col);
  }
}

// The trace's columns after the parameters, in the order Run writes them.
constexpr const char* kHealthColumns[] = {"trace_p", "prediction_error", "condition", "excitation",
                                          "frozen",  "wound_up",         "updates",   "rejected"};

// The largest parameter count run with a fixed-size estimator (the sizes instantiated).
constexpr int kMaxFixedParams = 8;

// What the recursion leaves for the JSON.
struct ArxRecursion {
  Eigen::VectorXd theta;
  Eigen::VectorXd std_dev;
  double last_prediction_error = 0.0;
  core::RlsHealth health;
};

// Rows first..end with an Rls<N> (N: the parameter count d, or Eigen::Dynamic); each step to the
// trace when it is on.
template <int N>
ArxRecursion Run(const core::RlsOptions& options, int d, const ArxData& data, Eigen::Index first,
                 const drivers::CsvTable& table, TraceWriter& trace) {
  core::Rls<N> rls(options, d);
  typename core::Rls<N>::Vector phi(d);
  const Eigen::VectorXd time_s = trace.enabled() ? table.time_s() : Eigen::VectorXd();
  std::vector<double> row(trace.enabled() ? static_cast<std::size_t>(d) + std::size(kHealthColumns)
                                          : 0);
  for (Eigen::Index t = first; t < data.y.size(); ++t) {
    FillRow(data, t, phi);
    rls.Update(phi, data.y(t));
    if (!trace.enabled()) continue;
    const core::RlsHealth& h = rls.health();
    for (int j = 0; j < d; ++j) row[static_cast<std::size_t>(j)] = rls.theta()(j);
    const double extra[std::size(kHealthColumns)] = {
        h.trace_p,
        rls.last_prediction_error(),
        h.condition_estimate,
        h.excitation,
        h.frozen ? 1.0 : 0.0,
        h.wound_up ? 1.0 : 0.0,
        static_cast<double>(h.updates),
        static_cast<double>(h.rejected_invalid + h.rejected_outliers)};
    std::copy(std::begin(extra), std::end(extra), row.begin() + d);
    trace.Row(time_s(t), row.data(), row.size());
  }
  ArxRecursion out;
  out.theta = rls.theta();
  typename core::Rls<N>::Vector std_dev(d);
  rls.StandardDeviations(std_dev);
  out.std_dev = std_dev;
  out.last_prediction_error = rls.last_prediction_error();
  out.health = rls.health();
  return out;
}

// Run<d> for d = N..kMaxFixedParams, Run<Dynamic> above.
template <int N>
ArxRecursion RunSized(const core::RlsOptions& options, int d, const ArxData& data,
                      Eigen::Index first, const drivers::CsvTable& table, TraceWriter& trace) {
  if constexpr (N > kMaxFixedParams) {
    return Run<Eigen::Dynamic>(options, d, data, first, table, trace);
  } else {
    if (d == N) return Run<N>(options, d, data, first, table, trace);
    return RunSized<N + 1>(options, d, data, first, table, trace);
  }
}

}  // namespace

nlohmann::json IdentifyOnlineArx(const IdentifyOptions& options, const drivers::CsvTable& table) {
  const ArxData data = ReadArxData(options, table);
  const std::vector<std::string>& inputs = data.inputs;
  const core::ArxOrders& orders = data.orders;
  const auto& y = data.y;
  const auto& u = data.u;
  const nlohmann::json& preprocessing = data.preprocessing;
  const int d = orders.num_parameters();
  const Eigen::Index first = orders.min_first_sample();
  const Eigen::Index n = y.size();
  if (n - first < d) {
    throw InputError(table.source() + ": " + std::to_string(n - first) + " equations for " +
                     std::to_string(d) + " ARX parameters");
  }
  const core::RlsOptions rls_options =
      core::RlsOptionsFor(OnlineSettingsFromFlags(options, table), d);
  std::vector<std::string> names;
  for (int j = 1; j <= orders.na; ++j) names.push_back("a" + std::to_string(j));
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    for (int j = 1; j <= orders.nb[i]; ++j) {
      names.push_back("b" + std::to_string(i + 1) + "_" + std::to_string(j));
    }
  }
  names.insert(names.end(), std::begin(kHealthColumns), std::end(kHealthColumns));
  TraceWriter trace(options.trace, names);
  const ArxRecursion recursion = RunSized<1>(rls_options, d, data, first, table, trace);
  trace.Close();

  // The snapshot in core::ArxModel form, so the JSON has the batch keys.  loss, aic and fpe are
  // those of the final parameters over the equations used (with forgetting 1: the batch ones).
  core::ArxModel model;
  model.orders = orders;
  model.parameters = recursion.theta;
  model.a = model.parameters.head(orders.na);
  Eigen::Index c = orders.na;
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    model.b.push_back(model.parameters.segment(c, orders.nb[i]));
    c += orders.nb[i];
  }
  model.parameter_std = recursion.std_dev;
  model.first_sample = first;
  model.num_samples = n - first;
  // Row by row, without the N x d regressor matrix (its pages cost more than the sums).
  double ssr = 0.0;
  Eigen::VectorXd phi(d);
  for (Eigen::Index t = first; t < n; ++t) {
    FillRow(data, t, phi);
    const double e = y(t) - phi.dot(model.parameters);
    ssr += e * e;
  }
  const double equations = static_cast<double>(n - first);
  const double ratio = d / equations;
  model.loss = ssr / equations;
  model.noise_variance = ssr / (equations - d);
  model.aic = std::log(model.loss) + 2.0 * ratio;
  model.fpe = model.loss * (1.0 + ratio) / (1.0 - ratio);
  nlohmann::json json = drivers::ToJson(model);
  if (!std::isfinite(model.aic)) json["aic"] = nullptr;
  json["inputs"] = inputs;
  json["output"] = options.y;
  json["sample_time_s"] = table.sample_time_s();
  json["preprocessing"] = preprocessing;
  json["estimator"] = "online-" + options.method;
  json["forgetting"] = options.forgetting;
  json["initial_covariance"] = rls_options.initial_covariance;
  json["prediction_error"] = recursion.last_prediction_error;
  json["health"] = RlsHealthJson(recursion.health);
  try {
    const Eigen::Index warmup = std::max<Eigen::Index>(model.first_sample, 1);
    // A record-length buffer in huge pages (LargeBuffer): its first touch is most of its cost.
    core::LargeBuffer buffer(static_cast<std::size_t>(n));
    Eigen::Map<Eigen::VectorXd> simulated(buffer.data(), n);
    core::SimulateArx(model, u, y.head(warmup), simulated);
    json["metrics"] = drivers::ToJson(core::ComputeMetrics(
        y.tail(n - warmup), simulated.tail(n - warmup), table.sample_time_s()));
  } catch (const std::invalid_argument& e) {
    throw InputError(table.source() + ": " + e.what());
  }
  return json;
}

}  // namespace canalid::cli
