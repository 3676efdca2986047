#pragma once
#include <nlohmann/json.hpp>
#include <optional>

#include "core/experiment/experiment_design.h"
#include "core/fractional/commensurate_state_space.h"
#include "core/fractional/fractional_foptd_fit.h"
#include "core/fractional/fractional_simulator.h"
#include "core/fractional/lpv_model.h"
#include "core/integrator_delay/identify_idz.h"
#include "core/integrator_delay/identify_integrator_delay.h"
#include "core/integrator_delay/integrator_delay_model.h"
#include "core/linear/arx.h"
#include "core/linear/process_model_fit.h"
#include "core/numerics/metrics.h"
#include "core/online/online_integrator_delay.h"
#include "core/online/online_model.h"
#include "core/reach/process_batch.h"

namespace canalid::drivers {

/// Model JSON (docs/design.md "Interfaces"): one object with "model" and self-describing keys in SI
/// units, plus "metrics".  These are the only places that name the keys, so `canalid identify`,
/// `canalid replay` and the daemon's state files agree.
nlohmann::json ToJson(const core::FitMetrics& metrics);
nlohmann::json ToJson(const core::IntegratorDelayFit& fit);
/// The ID model plus "preprocessing" (replaced level samples) and the correlation cross-check.
nlohmann::json ToJson(const core::IntegratorDelayIdentification& result);
/// "model": "idz": the IDZ fit with standard deviations and where p22 came from.
nlohmann::json ToJson(const core::IdzIdentification& result);
/// "model": "arx" with a, b_coeffs (one list per input), na, nb, nk, parameter_std, loss, aic, fpe.
nlohmann::json ToJson(const core::ArxModel& model);
/// The experiment design (amplitude, clock, order, periods, duration and the explanation).
nlohmann::json ToJson(const core::ExperimentDesign& design);
nlohmann::json ToJson(const core::FoptdFit& fit);
nlohmann::json ToJson(const core::SoptdFit& fit);
/// "model": "frac-foptd": gain, time_constant_s, alpha, delay_s, offsets, metrics, and the
/// Oustaloup band the fit simulated with ("oustaloup"), so a reader reproduces its output.
nlohmann::json ToJson(const core::FractionalFoptdFitResult& fit,
                      const core::OustaloupOptions& band);
/// "model": "frac-ss": q, alpha, the companion matrices A (rows), B, C, delay_samples, delay_s,
/// sample_time_s, offsets, memory_length (0 = full GL memory) and metrics.
nlohmann::json ToJson(const core::CommensurateFitResult& fit, double sample_time_s,
                      int memory_length);
/// "model": "lpv": kind, parameters (names in order), degree, coefficients (name -> polynomial,
/// highest degree first) and metrics_per_band (band, theta_mean, run start and length, local
/// parameters, local and LPV MAE).
nlohmann::json ToJson(const core::LpvIdentification& lpv, double sample_time_s);
/// A snapshot of the online ID bank in the ID model's keys ("model": "id", delay_s, nk, b,
/// area_m2, sample_time_s, p21_s_per_m2, offset_m, drift_m_per_s) with its standard deviations,
/// errors and "estimator": "online".
nlohmann::json OnlineIntegratorDelayJson(const core::IntegratorDelaySnapshot& snapshot,
                                         double sample_time_s);
/// A snapshot of any online model (core::OnlineModel) as published on LCM: "model" (the kind's
/// name), "estimator": "online", each parameter under its name with "<name>_std" where its
/// standard deviation is known, sample_time_s, samples_used, flags, trace_p, condition_number,
/// prediction_error_rms.
nlohmann::json OnlineModelJson(const core::OnlineModelSnapshot& snapshot, double sample_time_s);
/// An end-of-experiment process model (core::ProcessBatchResult): the model JSON of its kind
/// (foptd, frac-foptd with its Oustaloup band) plus sample_time_s; none when the fit gave no
/// model at all.
std::optional<nlohmann::json> ProcessBatchJson(const core::ProcessBatchResult& result,
                                               double sample_time_s);

}  // namespace canalid::drivers
