#pragma once
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace canalid::drivers {

/// One named parameter of a model JSON, as published in a model snapshot.
struct ModelJsonParam {
  std::string name;
  double value = 0.0;
  double std_dev = 0.0;  ///< NaN when the model gives none
};

/// The parameters a batch or persisted model JSON carries, flattened as `model_snapshot_t`
/// publishes them (docs/lcm-channels.md): the scalar keys (delay_s, area_m2, b, p21_s_per_m2,
/// p22_s_per_m2, offset_m, gain, time_constant_s, alpha) with their standard deviations where the
/// fit gives one, then arx's coefficients a1.., b1.. (one input) and soptd's time_constant_1_s,
/// time_constant_2_s.  Keys absent or not numbers are left out.
std::vector<ModelJsonParam> ModelJsonParams(const nlohmann::json& model);

}  // namespace canalid::drivers
