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
