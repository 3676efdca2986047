#include "drivers/json/model_json.h"

#include <cmath>

namespace canalid::drivers {

nlohmann::json ToJson(const core::FitMetrics& metrics) {
  return {{"rmse", metrics.rmse},
          {"mae", metrics.mae},
          {"fit_percent", metrics.fit_percent},
          {"ise", metrics.ise},
          {"norm_error", metrics.norm_error}};
}

nlohmann::json ToJson(const core::IntegratorDelayFit& fit) {
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

nlohmann::json ToJson(const core::IntegratorDelayIdentification& result) {
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

nlohmann::json ToJson(const core::IdzIdentification& result) {
  const core::IdzFit& fit = result.fit;
  const double ts = fit.sample_time_s;
  return {{"model", "idz"},
          {"delay_s", fit.delay_s()},
          {"nk", fit.nk},
          {"sample_time_s", ts},
          {"b", ts / fit.area_m2},
          {"area_m2", fit.area_m2},
          {"area_std_m2", fit.area_std_m2},
          {"p21_s_per_m2", fit.p21_s_per_m2},
          {"p21_std_s_per_m2", fit.p21_std_s_per_m2},
          {"p22_s_per_m2", fit.p22_s_per_m2},
          {"p22_std_s_per_m2", fit.p22_std_s_per_m2},
          {"p22_source", core::OutflowGainSourceName(fit.p22_source)},
          {"p22_reason", fit.p22_reason},
          {"outflow_moves", fit.outflow_moves},
          {"outflow_follows_level", fit.outflow_follows_level},
          {"outflow_level_correlation", fit.outflow_level_correlation},
          {"offset_m", fit.offset_m},
          {"drift_m_per_s", fit.drift_m_per_sample / ts},
          {"fit_from_sample", fit.first_sample},
          {"preprocessing", {{"level_outliers_replaced", result.level_outliers.count}}},
          {"metrics", ToJson(fit.metrics)},
          {"warnings", fit.warnings}};
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

namespace {
std::vector<double> ToVector(const Eigen::Ref<const Eigen::VectorXd>& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}
}  // namespace

nlohmann::json ToJson(const core::FractionalFoptdFitResult& fit,
                      const core::OustaloupOptions& band) {
  return {{"model", "frac-foptd"},
          {"gain", fit.params.gain},
          {"time_constant_s", fit.params.time_constant_s},
          {"alpha", fit.params.alpha},
          {"delay_s", fit.params.delay_s},
          {"input_offset", fit.input_offset},
          {"output_offset", fit.output_offset},
          {"initial",
           {{"gain", fit.initial.gain},
            {"time_constant_s", fit.initial.time_constant_s},
            {"alpha", fit.initial.alpha},
            {"delay_s", fit.initial.delay_s}}},
          {"converged", fit.converged},
          {"simulations", fit.simulations},
          {"oustaloup",
           {{"low_frequency_rad_s", band.low_frequency_rad_s},
            {"high_frequency_rad_s", band.high_frequency_rad_s},
            {"sections_per_decade", band.sections_per_decade}}},
          {"metrics", ToJson(fit.metrics)}};
}

nlohmann::json ToJson(const core::CommensurateFitResult& fit, double sample_time_s,
                      int memory_length) {
  const core::CommensurateModel& m = fit.model;
  const int n = m.order();
  nlohmann::json a = nlohmann::json::array();
  for (int i = 0; i < n; ++i) {
    std::vector<double> row(static_cast<std::size_t>(n), 0.0);
    if (i + 1 < n) row[static_cast<std::size_t>(i) + 1] = 1.0;
    // Last row -[a_n, ..., a_1].
    if (i + 1 == n) {
      for (int j = 0; j < n; ++j) row[static_cast<std::size_t>(j)] = -m.a(n - 1 - j);
    }
    a.push_back(row);
  }
  std::vector<double> b(static_cast<std::size_t>(n), 0.0);
  b.back() = m.a(n - 1);
  std::vector<double> c{1.0};
  for (Eigen::Index i = 0; i < m.c.size(); ++i) c.push_back(m.c(i));
  return {{"model", "frac-ss"},
          {"q", m.q},
          {"alpha", m.alpha()},
          {"A", a},
          {"B", b},
          {"C", c},
          {"delay_samples", m.delay_samples},
          {"delay_s", m.delay_samples * sample_time_s},
          {"sample_time_s", sample_time_s},
          {"memory_length", memory_length},
          {"input_offset", fit.input_offset},
          {"output_offset", fit.output_offset},
          {"converged", fit.converged},
          {"metrics", ToJson(fit.metrics)}};
}

nlohmann::json ToJson(const core::LpvIdentification& lpv, double sample_time_s) {
  const core::LpvModel& model = lpv.model;
  nlohmann::json coefficients = nlohmann::json::object();
  for (std::size_t i = 0; i < model.parameter_names.size(); ++i) {
    coefficients[model.parameter_names[i]] =
        ToVector(model.coefficients.row(static_cast<Eigen::Index>(i)).transpose());
  }
  nlohmann::json bands = nlohmann::json::array();
  for (const core::LpvOperatingPoint& p : lpv.points) {
    nlohmann::json local = nlohmann::json::object();
    const Eigen::VectorXd at_mean = model.Evaluate(p.theta_mean);
    nlohmann::json interpolated = nlohmann::json::object();
    for (std::size_t i = 0; i < model.parameter_names.size(); ++i) {
      local[model.parameter_names[i]] = p.local_params(static_cast<Eigen::Index>(i));
      interpolated[model.parameter_names[i]] = at_mean(static_cast<Eigen::Index>(i));
    }
    bands.push_back({{"theta_low", p.theta_low},
                     {"theta_high", p.theta_high},
                     {"theta_mean", p.theta_mean},
                     {"start_s", static_cast<double>(p.start) * sample_time_s},
                     {"samples", p.length},
                     {"local_params", local},
                     {"lpv_params", interpolated},
                     {"local_mae", p.local_mae},
                     {"lpv_mae", p.lpv_mae}});
  }
  return {{"model", "lpv"},
          {"kind", model.kind},
          {"parameters", model.parameter_names},
          {"degree", model.degree},
          {"coefficients", coefficients},
          {"metrics_per_band", bands}};
}

nlohmann::json OnlineIntegratorDelayJson(const core::IntegratorDelaySnapshot& s,
                                         double sample_time_s) {
  return {{"model", "id"},
          {"estimator", "online"},
          {"delay_s", s.delay_s},
          {"nk", s.delay_samples},
          {"b", s.b},
          {"area_m2", s.area_m2},
          {"sample_time_s", sample_time_s},
          {"p21_s_per_m2", s.wave_front_gain_s_per_m2},
          {"offset_m", s.c_m},
          {"drift_m_per_s", s.d_m / sample_time_s},
          {"b_std", s.b_std},
          {"area_std_m2", s.area_std_m2},
          {"prediction_error_m", s.prediction_error_m},
          {"innovation_std_m", s.innovation_std_m},
          {"flow_level_rms_m", s.flow_level_rms_m},
          {"flags", s.flags}};
}

nlohmann::json OnlineModelJson(const core::OnlineModelSnapshot& s, double sample_time_s) {
  nlohmann::json j = {{"model", core::OnlineModelKindName(s.kind)}, {"estimator", "online"}};
  for (std::size_t i = 0; i < static_cast<std::size_t>(s.num_params); ++i) {
    j[s.names[i]] = s.values[i];
    if (std::isfinite(s.std_devs[i])) j[s.names[i] + "_std"] = s.std_devs[i];
  }
  j["sample_time_s"] = sample_time_s;
  j["samples_used"] = s.samples_used;
  j["flags"] = s.flags;
  j["trace_p"] = s.trace_p;
  j["condition_number"] = s.condition_number;
  j["prediction_error_rms"] = s.prediction_error_rms;
  return j;
}

std::optional<nlohmann::json> ProcessBatchJson(const core::ProcessBatchResult& result,
                                               double sample_time_s) {
  nlohmann::json json;
  if (result.foptd) {
    json = ToJson(*result.foptd);
  } else if (result.soptd) {
    json = ToJson(*result.soptd);
  } else if (result.arx) {
    // The model of the deviations from the record's rest point, with its delay in seconds and
    // the rest point as the offsets (as the process fits give them).
    json = ToJson(*result.arx);
    if (!std::isfinite(result.arx->aic)) json.erase("aic");
    json["delay_s"] = result.arx->orders.nk.front() * sample_time_s;
    json["input_offset"] = result.input_offset;
    json["output_offset"] = result.output_offset;
  } else if (result.fractional) {
    json = ToJson(*result.fractional, result.band);
  } else if (result.commensurate) {
    json = ToJson(*result.commensurate, sample_time_s, result.memory_samples);
  } else {
    return std::nullopt;
  }
  json["sample_time_s"] = sample_time_s;
  return json;
}

}  // namespace canalid::drivers
