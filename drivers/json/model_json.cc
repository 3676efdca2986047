#include "drivers/json/model_json.h"

namespace canalid::drivers {

nlohmann::json ToJson(const core::FitMetrics& metrics) {
  return {{"rmse", metrics.rmse},
          {"mae", metrics.mae},
          {"fit_percent", metrics.fit_percent},
          {"ise", metrics.ise},
          {"norm_error", metrics.norm_error}};
}

nlohmann::json ToJson(const core::IdFitResult& fit) {
  const double ts = fit.model.sample_time_s;
  return {{"model", "id"},
          {"delay_s", fit.model.delay_s()},
          {"nk", fit.model.nk},
          {"b", fit.model.b},
          {"area_m2", fit.model.area_m2()},
          {"sample_time_s", ts},
          {"p21_s_per_m2", fit.wave_front_gain_s_per_m2},
          {"offset_m", fit.offset_m},
          {"drift_m_per_s", fit.drift_m_per_sample / ts},
          {"closed_loop", fit.closed_loop},
          {"closed_loop_reason", fit.closed_loop_reason},
          {"cross_check",
           {{"iv_area_m2", fit.iv_area_m2},
            {"open_loop_area_m2", fit.open_loop_area_m2},
            {"outflow_level_correlation", fit.outflow_level_correlation}}},
          {"fit_from_sample", fit.first_sample},
          {"metrics", ToJson(fit.metrics)},
          {"warnings", fit.warnings}};
}

nlohmann::json ToJson(const core::IdPipelineResult& result) {
  nlohmann::json json = ToJson(result.fit);
  const double ts = result.fit.model.sample_time_s;
  const auto& replaced = result.level_outliers.replaced;
  json["preprocessing"] = {{"level_outliers_replaced", result.level_outliers.count},
                           {"level_outlier_times_s", nlohmann::json::array()}};
  for (std::size_t i = 0; i < replaced.size() && i < 20; ++i) {
    json["preprocessing"]["level_outlier_times_s"].push_back(static_cast<double>(replaced[i]) * ts);
  }
  if (result.correlation.num_samples > 0) {
    const int lag = result.correlation.first_significant_lag;
    json["cross_check"]["correlation_first_significant_delay_s"] =
        lag >= 0 ? nlohmann::json(lag * ts) : nlohmann::json();
    json["cross_check"]["correlation_peak_delay_s"] = result.correlation.peak_lag * ts;
  }
  return json;
}

nlohmann::json ToJson(const core::ArxModel& model) {
  nlohmann::json b = nlohmann::json::array();
  for (const auto& coefficients : model.b) {
    b.push_back(
        std::vector<double>(coefficients.data(), coefficients.data() + coefficients.size()));
  }
  return {{"model", "arx"},
          {"na", model.orders.na},
          {"nb", model.orders.nb},
          {"nk", model.orders.nk},
          {"a", std::vector<double>(model.a.data(), model.a.data() + model.a.size())},
          {"b_coeffs", b},
          {"parameter_std",
           std::vector<double>(model.parameter_std.data(),
                               model.parameter_std.data() + model.parameter_std.size())},
          {"loss", model.loss},
          {"aic", model.aic},
          {"fpe", model.fpe},
          {"fit_from_sample", model.first_sample},
          {"equations", model.num_samples}};
}

nlohmann::json ToJson(const core::ExperimentDesign& design) {
  return {{"amplitude", design.amplitude_m3s},
          {"clock_period_s", design.clock_period_s},
          {"clock_period_samples", design.clock_period_samples},
          {"order", design.order},
          {"num_periods", design.num_periods},
          {"num_samples", design.num_samples},
          {"duration_s", design.duration_s},
          {"explanation", design.explanation}};
}

nlohmann::json ToJson(const core::FoptdFit& fit) {
  return {{"model", "foptd"},
          {"gain", fit.model.gain},
          {"time_constant_s", fit.model.time_constant_s},
          {"delay_s", fit.model.delay_s},
          {"input_offset", fit.input_offset},
          {"output_offset", fit.output_offset},
          {"metrics", ToJson(fit.metrics)}};
}

nlohmann::json ToJson(const core::SoptdFit& fit) {
  return {{"model", "soptd"},
          {"gain", fit.model.gain},
          {"time_constants_s", {fit.model.time_constants_s[0], fit.model.time_constants_s[1]}},
          {"delay_s", fit.model.delay_s},
          {"input_offset", fit.input_offset},
          {"output_offset", fit.output_offset},
          {"metrics", ToJson(fit.metrics)}};
}

}  // namespace canalid::drivers
