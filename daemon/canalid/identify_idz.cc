#include <stdexcept>

#include "core/integrator_delay/identify_idz.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/pool_theory.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {
namespace {

struct Prior {
  double p22 = -1.0;
  double std = 0.0;
  nlohmann::json json;
};

Prior TheoryPrior(const IdentifyOptions& options, double flow_m3s) {
  const core::IdzTheory theory = PoolTheory(options.canal, options.pool, flow_m3s);
  Prior prior;
  prior.p22 = theory.outflow_gain_low_frequency_s_per_m2;
  prior.json = {{"from", "theory"},
                {"canal", options.canal},
                {"pool", options.pool},
                {"flow_m3s", flow_m3s},
                {"theory_area_m2", theory.model.area_m2},
                {"theory_delay_s", theory.model.delay_s}};
  return prior;
}

}  // namespace

nlohmann::json IdentifyIdz(const IdentifyOptions& options, const drivers::CsvTable& table) {
  if (options.p22 >= 0.0 && !options.canal.empty()) {
    throw InputError("--p22 and --canal both give the p22 prior: give one");
  }
  const Eigen::VectorXd q_in = RequireMovingColumn(table, options.qin);
  const Eigen::VectorXd q_out = RequireColumn(table, options.qout);
  const Eigen::VectorXd level = RequireColumn(table, options.level);
  const double ts = table.sample_time_s();
  Prior prior;
  if (!options.canal.empty()) {
    prior = TheoryPrior(options, q_in.mean());
  } else if (options.p22 >= 0.0) {
    prior.p22 = options.p22;
    prior.json = {{"from", "--p22"}};
  } else if (options.p22_std >= 0.0) {
    throw InputError("--p22-std needs a prior: --p22 or --canal with --pool");
  }
  core::IdzIdentificationOptions pipeline;
  pipeline.remove_level_outliers = !options.keep_outliers;
  if (options.max_delay_s > 0.0) {
    pipeline.fit.max_nk = OptionSamples(options.max_delay_s, table, "--max-delay-s", false);
  }
  if (prior.p22 >= 0.0) {
    prior.std = options.p22_std >= 0.0 ? options.p22_std : core::kIdzPriorRelativeStd * prior.p22;
    pipeline.fit.p22_prior_s_per_m2 = prior.p22;
    pipeline.fit.p22_prior_std_s_per_m2 = prior.std;
    prior.json["p22_s_per_m2"] = prior.p22;
    prior.json["p22_std_s_per_m2"] = prior.std;
  }
  nlohmann::json json;
  try {
    json = drivers::ToJson(core::IdentifyIdz(q_in, q_out, level, ts, pipeline));
  } catch (const std::invalid_argument& e) {
    throw InputError(table.source() + ": " + e.what());
  }
  json["p22_prior"] = prior.p22 >= 0.0 ? prior.json : nlohmann::json();
  return json;
}

}  // namespace canalid::cli
