#pragma once
// An RLS estimator's health as the JSON of `canalid identify --online` (docs/model-json.md).
#include <nlohmann/json.hpp>

#include "core/online/rls_options.h"

namespace canalid::cli {

nlohmann::json RlsHealthJson(const core::RlsHealth& h);

}  // namespace canalid::cli
