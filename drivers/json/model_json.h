#pragma once
#include <nlohmann/json.hpp>

#include "core/arx.h"
#include "core/experiment_design.h"
#include "core/id_model.h"
#include "core/id_pipeline.h"
#include "core/metrics.h"
#include "core/process_model_fit.h"

namespace canalid::drivers {

/// Model JSON (DESIGN.md "Interfaces"): one object with "model" and self-describing keys in SI
/// units, plus "metrics".  These are the only places that name the keys, so `canalid identify`,
/// `canalid replay` and the daemon's state files agree.
nlohmann::json ToJson(const core::FitMetrics& metrics);
nlohmann::json ToJson(const core::IdFitResult& fit);
/// The ID model plus "preprocessing" (replaced level samples) and the correlation cross-check.
nlohmann::json ToJson(const core::IdPipelineResult& result);
/// "model": "arx" with a, b_coeffs (one list per input), na, nb, nk, parameter_std, loss, aic, fpe.
nlohmann::json ToJson(const core::ArxModel& model);
/// The experiment design (amplitude, clock, order, periods, duration and the explanation).
nlohmann::json ToJson(const core::ExperimentDesign& design);
nlohmann::json ToJson(const core::FoptdFit& fit);
nlohmann::json ToJson(const core::SoptdFit& fit);

}  // namespace canalid::drivers
