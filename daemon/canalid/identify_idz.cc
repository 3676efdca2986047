#include <stdexcept>

#include "core/integrator_delay/identify_idz.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/pool_theory.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {

double IdzP22Prior(const IdentifyOptions& options, double mean_inflow_m3s, nlohmann::json* prior) {
  if (options.p22 >= 0.0 && !options.canal.empty()) {
    throw InputError("--p22 and --canal both give the p22 prior: give one");
  }
  *prior = nullptr;
  if (!options.canal.empty()) {
    const core::IdzTheory theory = PoolTheory(options.canal, options.pool, mean_inflow_m3s);
    *prior = {{"from", "theory"},
              {"canal", options.canal},
              {"pool", options.pool},
              {"flow_m3s", mean_inflow_m3s},
              {"theory_area_m2", theory.model.area_m2},
              {"theory_delay_s", theory.model.delay_s}};
    return theory.outflow_gain_low_frequency_s_per_m2;
  }
  if (options.p22 >= 0.0) {
    *prior = {{"from", "--p22"}};
    return options.p22;
  }
  if (options.p22_std >= 0.0) {
    throw InputError("--p22-std needs a prior: --p22 or --canal with --pool");
  }
  return -1.0;
}

nlohmann::json IdentifyIdz(const IdentifyOptions& options, const drivers::CsvTable& table) {
  const auto q_in = RequireMovingColumn(table, options.qin);
  const auto q_out = RequireColumn(table, options.qout);
  const auto level = RequireColumn(table, options.level);
  const double ts = table.sample_time_s();
  // The p22 prior and what it came from (the theory at the record's mean inflow, or --p22).
  nlohmann::json prior;
  const double p22 = IdzP22Prior(options, q_in.mean(), &prior);
  core::IdzIdentificationOptions pipeline;
  pipeline.remove_level_outliers = !options.keep_outliers;
  if (options.max_delay_s > 0.0) {
    pipeline.fit.max_nk = OptionSamples(options.max_delay_s, table, "--max-delay-s", false);
  }
  if (p22 >= 0.0) {
    const double std = options.p22_std >= 0.0 ? options.p22_std : core::kIdzPriorRelativeStd * p22;
    pipeline.fit.p22_prior_s_per_m2 = p22;
    pipeline.fit.p22_prior_std_s_per_m2 = std;
    prior["p22_s_per_m2"] = p22;
    prior["p22_std_s_per_m2"] = std;
  }
  nlohmann::json json;
  try {
    json = drivers::ToJson(core::IdentifyIdz(q_in, q_out, level, ts, pipeline));
  } catch (const std::invalid_argument& e) {
    throw InputError(table.source() + ": " + e.what());
  }
  json["p22_prior"] = prior;  // null without a prior
  return json;
}

}  // namespace canalid::cli
