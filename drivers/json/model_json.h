#pragma once
#include <nlohmann/json.hpp>

#include "core/id_model.h"
#include "core/metrics.h"
#include "core/process_model_fit.h"

namespace canalid::drivers {

/// Model JSON (DESIGN.md "Interfaces"): one object with "model" and self-describing keys in SI
/// units, plus "metrics".  These are the only places that name the keys, so `canalid identify`,
/// `canalid replay` and the daemon's state files agree.
nlohmann::json ToJson(const core::FitMetrics& metrics);
nlohmann::json ToJson(const core::IdFitResult& fit);
nlohmann::json ToJson(const core::FoptdFit& fit);
nlohmann::json ToJson(const core::SoptdFit& fit);

}  // namespace canalid::drivers
