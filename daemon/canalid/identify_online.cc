// `canalid identify --model id|arx --online` (arx: identify_online_arx.cc): the recursive
// estimators of core/ run sample by sample over a CSV record, as the daemon runs them, and their
// final snapshot printed in the batch model's JSON keys (docs/model-json.md) plus `estimator` and
// `health`.
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/integrator_delay/identify_integrator_delay.h"
#include "core/online/online_integrator_delay.h"
#include "core/online/online_model.h"
#include "daemon/canalid/closed_loop_option.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/online_settings_flags.h"
#include "daemon/canalid/rls_health_json.h"
#include "daemon/canalid/table_columns.h"
#include "daemon/canalid/trace_writer.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {
namespace {

nlohmann::json OnlineId(const IdentifyOptions& options, const drivers::CsvTable& table) {
  const auto q_in = RequireMovingColumn(table, options.qin);
  const auto q_out = RequireColumn(table, options.qout);
  Eigen::VectorXd level = RequireColumn(table, options.level);
  const double ts = table.sample_time_s();
  const auto n = level.size();
  // The batch pipeline's cleaning, so online and batch see the same level.
  const core::IntegratorDelayIdentificationOptions pipeline;
  core::OutlierReport outliers;
  if (!options.keep_outliers) {
    core::OutlierResult cleaned = core::RemoveOutliers(level, pipeline.level_outliers);
    level = cleaned.cleaned;
    outliers = cleaned.report;
  }
  // The id kind's options through the registry's one function (the daemon's), from the flags.
  core::OnlineModelSettings settings = OnlineSettingsFromFlags(options, table);
  const int max_delay_samples =
      options.max_delay_s > 0.0 ? OptionSamples(options.max_delay_s, table, "--max-delay-s", false)
                                : static_cast<int>(n / 3);
  settings.min_delay_s = 0.0;
  settings.max_delay_s = max_delay_samples * ts;
  // With p21 >= 0 as in the batch fit: a negative wave-front gain lets Q_(nk-1) - b q_in(k-nk+1)
  // mimic Q_nk, so the delay would be ambiguous by one sample.
  settings.wave_front_term = true;
  // on (three-step) = the recursive three-step method (core::OnlineThreeStep), iv =
  // instrumental-variable RLS, off = least squares, auto = IV and LS over the first samples, then
  // FitIntegratorDelay's closed-loop test picks one (core::OnlineIntegratorDelayOptions).
  settings.closed_loop = ParseClosedLoop(options.closed_loop);
  settings.p22_s_per_m2 = std::max(options.p22, 0.0);  // not given: plain ID
  core::OnlineIntegratorDelayOptions id;
  try {
    id = core::OnlineModelOptionsFor(core::OnlineModelKind::kIntegratorDelay, settings).id;
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  if (id.max_delay_samples + 20 >= n) {
    throw InputError(table.source() + ": " + std::to_string(n) +
                     " samples are too few for delays up to " +
                     std::to_string(id.max_delay_samples) + " samples (--max-delay-s)");
  }
  // auto decides over the first 200 regression samples, or all of them on a shorter record, so
  // that a record always ends decided.
  id.closed_loop_window_samples =
      static_cast<int>(std::min<Eigen::Index>(200, n - id.max_delay_samples - 1));
  std::unique_ptr<core::OnlineIntegratorDelayBank> bank;
  try {
    bank = std::make_unique<core::OnlineIntegratorDelayBank>(id);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  const Eigen::VectorXd time_s = table.time_s();
  TraceWriter trace(options.trace,
                    {"delay_s", "area_m2", "b", "p21_s_per_m2", "offset_m", "drift_m_per_s",
                     "trace_p", "prediction_error", "condition", "excitation", "frozen", "wound_up",
                     "updates", "rejected", "switches"});
  for (Eigen::Index k = 0; k < n; ++k) {
    bank->Update(q_in(k), q_out(k), level(k));
    if (!trace.enabled()) continue;
    const core::IntegratorDelaySnapshot s = bank->Snapshot();
    if (!s.valid) continue;
    const double row[] = {
        s.delay_s,
        s.area_m2,
        s.b,
        s.wave_front_gain_s_per_m2,
        s.c_m,
        s.d_m / ts,
        s.health.trace_p,
        s.prediction_error_m,
        s.health.condition_estimate,
        s.health.excitation,
        s.health.frozen ? 1.0 : 0.0,
        s.health.wound_up ? 1.0 : 0.0,
        static_cast<double>(s.health.updates),
        static_cast<double>(s.health.rejected_invalid + s.health.rejected_outliers),
        static_cast<double>(bank->health().switches)};
    trace.Row(time_s(k), row, std::size(row));
  }
  trace.Close();
  const core::IntegratorDelaySnapshot s = bank->Snapshot();
  if (!s.valid) throw InputError(table.source() + ": the online bank made no estimate");
  const core::IntegratorDelayBankHealth& bank_health = bank->health();
  nlohmann::json health = RlsHealthJson(s.health);
  health["samples"] = bank_health.samples;
  health["bad_flow_samples"] = bank_health.bad_flow_samples;
  health["bad_level_samples"] = bank_health.bad_level_samples;
  health["dropped_samples"] = bank_health.dropped_samples;
  health["switches"] = bank_health.switches;
  health["candidates"] = bank->num_candidates();
  std::string reason = id.closed_loop == core::ClosedLoopMode::kOff ? "disabled" : "requested";
  if (id.closed_loop == core::ClosedLoopMode::kAuto) {
    reason = !bank_health.closed_loop_decided
                 ? "undecided: fewer than " + std::to_string(id.closed_loop_window_samples) +
                       " samples after the longest delay"
                 : std::string(bank_health.outflow_moves ? "outflow moves" : "outflow held") +
                       ", outflow-level correlation " +
                       std::to_string(bank_health.outflow_level_correlation) + " over " +
                       std::to_string(id.closed_loop_window_samples) + " samples";
  }
  // The online ID model's keys, then what this command adds; "estimator" names the method used.
  nlohmann::json model = drivers::OnlineIntegratorDelayJson(s, ts);
  model["p22_s_per_m2"] = id.outflow_direct_gain_s_per_m2;
  model["closed_loop"] = bank_health.closed_loop;
  model["closed_loop_reason"] = reason;
  model["fit_from_sample"] = id.max_delay_samples + 1;
  model["estimator"] = id.closed_loop == core::ClosedLoopMode::kThreeStep ? "online-three-step"
                       : bank_health.closed_loop                          ? "online-iv"
                                                 : "online-" + options.method;
  model["forgetting"] = options.forgetting;
  model["initial_covariance"] = id.rls.initial_covariance;
  model["health"] = health;
  model["preprocessing"] = {{"level_outliers_replaced", outliers.count}};
  model["warnings"] = nlohmann::json::array();
  return model;
}

}  // namespace

nlohmann::json IdentifyOnline(const IdentifyOptions& options, const drivers::CsvTable& table) {
  if (!options.config.empty()) return IdentifyOnlineModel(options, table);
  if (options.model == "id") return OnlineId(options, table);
  if (options.model == "arx") return IdentifyOnlineArx(options, table);
  return IdentifyOnlineModel(options, table);
}

}  // namespace canalid::cli
