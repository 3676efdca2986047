#include "core/fractional/fractional_foptd.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/fractional/mittag_leffler.h"

namespace canalid::core {

void Validate(const FractionalFoptdParams& params) {
  if (!std::isfinite(params.gain)) {
    throw std::invalid_argument("FractionalFoptdParams: gain must be finite");
  }
  if (!(params.time_constant_s > 0.0) || !std::isfinite(params.time_constant_s)) {
    throw std::invalid_argument("FractionalFoptdParams: time_constant_s = " +
                                std::to_string(params.time_constant_s) + " must be > 0");
  }
  if (!(params.alpha > 0.0 && params.alpha < 2.0)) {
    throw std::invalid_argument("FractionalFoptdParams: alpha = " + std::to_string(params.alpha) +
                                " must be in (0, 2)");
  }
  if (!(params.delay_s >= 0.0) || !std::isfinite(params.delay_s)) {
    throw std::invalid_argument(
        "FractionalFoptdParams: delay_s = " + std::to_string(params.delay_s) + " must be >= 0");
  }
}

double FractionalFoptdStepResponse(const FractionalFoptdParams& params, double t_s) {
  Validate(params);
  const double t = t_s - params.delay_s;
  if (t <= 0.0) return 0.0;
  return params.gain *
         (1.0 - MittagLeffler(params.alpha, -std::pow(t, params.alpha) / params.time_constant_s));
}

}  // namespace canalid::core
