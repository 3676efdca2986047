#pragma once
#include <nlohmann/json.hpp>

namespace canalid::testing {

/// The smallest LPV model JSON a reader takes: y(k) = 0.7 y(k-1) + 0.1 u(k-3) along theta
/// (first-order ARX locals, degree 0: one local model), no offsets, no sample time.
inline nlohmann::json MinimalLpvJson() {
  return {{"model", "lpv"},
          {"kind", "first_order_arx"},
          {"local_model", "arx"},
          {"schedule", "theta"},
          {"degree", 0},
          {"parameters", {"a1", "b1", "nk"}},
          {"coefficients", {{"a1", {-0.7}}, {"b1", {0.1}}, {"nk", {3.0}}}}};
}

}  // namespace canalid::testing
