// `canalid identify --online` through the online model registry (core/online/online_model.h), the
// estimators the daemon runs: --model frac-foptd|lpv with the command's flags, and any registry
// kind with --config FILE --reach NAME, which takes the reach's settings and channel columns from
// a canalidd configuration, so that the result equals the daemon's on the same samples.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/online/online_model.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/online_settings_flags.h"
#include "daemon/canalid/table_columns.h"
#include "daemon/canalid/trace_writer.h"
#include "daemon/config/config_loader.h"
#include "daemon/config/plan_from_config.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {
namespace {

// The signals of the registry's OnlineSample, one column each (empty: not used by the kind).
struct OnlineColumns {
  Eigen::VectorXd q_in, q_out, level, input, scheduling;
};

int SingleInteger(const std::string& option, const std::string& text) {
  try {
    std::size_t used = 0;
    const int value = std::stoi(text, &used);
    if (used == text.size()) return value;
  } catch (const std::exception&) {
  }
  throw InputError(option + " " + text + ": expected one integer (online: a single input)");
}

// idz: the flows and the level, delays 0..--max-delay-s (default a third of the record, as the
// online id bank), the p22 prior held.
core::OnlineModelSettings IdzSettings(const IdentifyOptions& o, const drivers::CsvTable& table,
                                      core::OnlineModelSettings s, OnlineColumns& c) {
  if (o.p22_std >= 0.0) {
    throw InputError("--p22-std applies to the batch idz fit (--online holds p22 at the prior)");
  }
  c.q_in = RequireMovingColumn(table, o.qin);
  c.q_out = RequireColumn(table, o.qout);
  c.level = RequireColumn(table, o.level);
  s.min_delay_s = 0.0;
  s.max_delay_s = o.max_delay_s > 0.0
                      ? o.max_delay_s
                      : std::floor(static_cast<double>(table.rows()) / 3.0) * s.sample_time_s;
  nlohmann::json prior;
  s.idz_p22_s_per_m2 = std::max(IdzP22Prior(o, c.q_in.mean(), &prior), 0.0);
  return s;
}

core::OnlineModelSettings SettingsFromFlags(const IdentifyOptions& o,
                                            const drivers::CsvTable& table, OnlineColumns& c) {
  core::OnlineModelSettings s = OnlineSettingsFromFlags(o, table);
  if (o.model == "idz") return IdzSettings(o, table, s, c);
  const int nk = SingleInteger("--nk", o.nk);
  if (nk < 0 || nk >= table.rows() / 2) {
    throw InputError("--nk " + o.nk + ": out of range (0 <= nk < half the record's " +
                     std::to_string(table.rows()) + " rows)");
  }
  c.input = RequireMovingColumn(table, o.u);
  c.level = RequireColumn(table, o.y);
  if (o.model == "frac-foptd") {
    if (o.q > 0) throw InputError("--q applies to --model frac-ss, not frac-foptd");
    if (o.alpha > 0.0) s.fractional_alphas = {o.alpha};
    s.fractional_delay_s = nk * s.sample_time_s;
  } else if (o.model == "frac-ss") {
    if (o.alpha > 0.0) {
      throw InputError("--alpha applies to --model frac-foptd; frac-ss takes --q (alpha = 1/q)");
    }
    s.frac_ss_q = o.q > 0 ? o.q : 2;  // the batch fit's default
    s.frac_ss_delay_s = nk * s.sample_time_s;
  } else {
    if (o.schedule.empty()) throw InputError("--model lpv --online: give --schedule COLUMN");
    c.scheduling = RequireColumn(table, o.schedule);
    s.lpv_na = o.na;
    s.lpv_nb = SingleInteger("--nb", o.nb);
    s.lpv_delay_s = nk * s.sample_time_s;
  }
  return s;
}

core::OnlineModelSettings SettingsFromConfig(const IdentifyOptions& o,
                                             const drivers::CsvTable& table, OnlineColumns& c) {
  config::DaemonConfig daemon_config;
  try {
    daemon_config = daemon::LoadDaemonConfig(o.config);
  } catch (const daemon::ConfigError& e) {
    throw InputError(std::string("--config: ") + e.what());
  }
  const config::ReachConfig* reach = daemon_config.FindReach(o.reach);
  if (reach == nullptr) {
    std::string names;
    for (const auto& r : daemon_config.reaches) names += (names.empty() ? "" : ", ") + r.name;
    throw InputError("--reach " + o.reach + ": not a reach of " + o.config + " (" + names + ")");
  }
  core::OnlineModelSettings s = config::BuildOnlineModelSettings(daemon_config, *reach);
  // The record must be sampled as the daemon samples the reach (canalid export writes it so).
  const double ts = table.sample_time_s();
  if (std::abs(ts - s.sample_time_s) > 1e-9 * s.sample_time_s) {
    throw InputError(table.source() + ": sampled every " + std::to_string(ts) + " s, reach " +
                     o.reach + " every " + std::to_string(s.sample_time_s) + " s");
  }
  c.q_in = RequireColumn(table, reach->inflow);
  c.q_out = RequireColumn(table, reach->outflow);
  c.level = RequireColumn(table, reach->level);
  c.input = RequireColumn(
      table, reach->actuator_position.empty() ? reach->actuator : reach->actuator_position);
  if (!reach->lpv_scheduling.empty()) c.scheduling = RequireColumn(table, reach->lpv_scheduling);
  return s;
}

double At(const Eigen::VectorXd& column, Eigen::Index k) {
  return column.size() > 0 ? column(k) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

nlohmann::json IdentifyOnlineModel(const IdentifyOptions& options, const drivers::CsvTable& table) {
  const auto kind = core::OnlineModelKindFromName(options.model);
  if (!kind) {
    throw InputError("--online: --model " + options.model +
                     " has no online estimator (online: id, arx, frac-foptd, lpv, idz, frac-ss)");
  }
  OnlineColumns columns;
  const core::OnlineModelSettings settings = options.config.empty()
                                                 ? SettingsFromFlags(options, table, columns)
                                                 : SettingsFromConfig(options, table, columns);
  std::unique_ptr<core::OnlineModel> model;
  try {
    model = core::MakeOnlineModel(core::OnlineModelOptionsFor(*kind, settings));
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  core::OnlineModelSnapshot snapshot;
  model->FillSnapshot(snapshot);
  std::vector<std::string> names;
  for (const std::string& name : snapshot.names) {
    names.push_back(name);
    names.push_back(name + "_std");
  }
  names.insert(names.end(), {"trace_p", "condition_number", "prediction_error_rms", "flags"});
  TraceWriter trace(options.trace, names);
  std::vector<double> row(names.size());
  const Eigen::VectorXd time_s = table.time_s();
  for (Eigen::Index k = 0; k < table.rows(); ++k) {
    const core::OnlineSample sample{At(columns.q_in, k), At(columns.q_out, k), At(columns.level, k),
                                    At(columns.input, k), At(columns.scheduling, k)};
    model->Update(sample);
    if (!trace.enabled()) continue;
    model->FillSnapshot(snapshot);
    if (!snapshot.valid) continue;
    std::size_t i = 0;
    for (std::size_t p = 0; p < snapshot.names.size(); ++p) {
      row[i++] = snapshot.values[p];
      row[i++] = snapshot.std_devs[p];
    }
    row[i++] = snapshot.trace_p;
    row[i++] = snapshot.condition_number;
    row[i++] = snapshot.prediction_error_rms;
    row[i++] = snapshot.flags;
    trace.Row(time_s(k), row.data(), row.size());
  }
  trace.Close();
  model->FillSnapshot(snapshot);
  if (!snapshot.valid) throw InputError(table.source() + ": the online estimator made no estimate");
  nlohmann::json json = drivers::OnlineModelJson(snapshot, table.sample_time_s());
  json["method"] = config::EnumName(settings.rls_method);
  json["forgetting"] = settings.forgetting;
  json["initial_covariance"] =
      settings.initial_covariance.value_or(core::kDefaultInitialCovariance);
  if (!options.config.empty()) json["reach"] = options.reach;
  return json;
}

}  // namespace canalid::cli
