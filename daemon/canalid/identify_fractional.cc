#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/fractional/commensurate_state_space.h"
#include "core/fractional/fractional_foptd_fit.h"
#include "core/fractional/fractional_simulator.h"
#include "daemon/canalid/identify_command.h"
#include "daemon/canalid/input_error.h"
#include "daemon/canalid/table_columns.h"
#include "drivers/json/model_json.h"

namespace canalid::cli {
namespace {

// --alpha holds alpha: the fit's bounds are closed around it (the options need min < max).
constexpr double kFixedAlphaHalfWidth = 1e-9;

nlohmann::json FitFractionalFoptd(const IdentifyOptions& options, const Eigen::VectorXd& u,
                                  const Eigen::VectorXd& y, double ts) {
  core::FractionalFoptdFitOptions fit;
  if (options.alpha > 0.0) {
    fit.alpha_min = options.alpha - kFixedAlphaHalfWidth;
    fit.alpha_max = options.alpha + kFixedAlphaHalfWidth;
  }
  if (options.max_delay_s > 0.0) fit.max_delay_s = options.max_delay_s;
  const core::FractionalFoptdFitResult result = core::FitFractionalFoptd(u, y, ts, fit);
  // The band the fit simulated with (it depends on T, alpha and the record length), recorded so
  // that `canalid simulate` reproduces the fitted output exactly.
  const core::OustaloupOptions band = core::FitOustaloupBand(result.params, ts, u.size(), fit);
  nlohmann::json json = drivers::ToJson(result, band);
  json["alpha_fixed"] = options.alpha > 0.0;
  return json;
}

// max_delay_samples < 0: the default min(record / 10, 100 samples).
nlohmann::json FitCommensurate(const IdentifyOptions& options, const Eigen::VectorXd& u,
                               const Eigen::VectorXd& y, double ts, int max_delay_samples) {
  const int q = options.q > 0 ? options.q : 2;
  const Eigen::Index n = u.size();
  const int max_delay = max_delay_samples >= 0
                            ? max_delay_samples
                            : static_cast<int>(std::min<Eigen::Index>(n / 10, 100));
  core::CommensurateFitOptions fit;
  const core::CommensurateFitResult result =
      core::FitCommensurateScanDelay(u, y, q, max_delay, ts, fit);
  return drivers::ToJson(result, ts, fit.memory_length);
}

}  // namespace

nlohmann::json IdentifyFractional(const IdentifyOptions& options, const drivers::CsvTable& table) {
  if (options.model == "frac-foptd" && options.q > 0) {
    throw InputError("--q applies to --model frac-ss, not frac-foptd");
  }
  if (options.model == "frac-ss" && options.alpha > 0.0) {
    throw InputError("--alpha applies to --model frac-foptd; frac-ss takes --q (alpha = 1/q)");
  }
  const Eigen::VectorXd u = RequireMovingColumn(table, options.u);
  const Eigen::VectorXd y = RequireColumn(table, options.y);
  const int max_delay_samples =
      options.model == "frac-ss" && options.max_delay_s > 0.0
          ? OptionSamples(options.max_delay_s, table, "--max-delay-s", true)
          : -1;
  try {
    return options.model == "frac-foptd"
               ? FitFractionalFoptd(options, u, y, table.sample_time_s())
               : FitCommensurate(options, u, y, table.sample_time_s(), max_delay_samples);
  } catch (const std::invalid_argument& e) {
    throw InputError(table.source() + ": " + e.what());
  }
}

}  // namespace canalid::cli
