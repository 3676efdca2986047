#pragma once

namespace canalid::core {

/// Fractional first order plus time delay (the flume paper):  G(s) = K e^{-tau s} / (1 + T
/// s^alpha). alpha = 1 is the ordinary FOPTD.  Units: gain in output units per input unit, seconds.
struct FractionalFoptdParams {
  double gain = 1.0;             ///< K, static gain (any sign, finite)
  double time_constant_s = 1.0;  ///< T > 0 [s^alpha]
  double alpha = 1.0;            ///< 0 < alpha < 2
  double delay_s = 0.0;          ///< tau >= 0
};

/// @throws std::invalid_argument naming the field, value and allowed range.
void Validate(const FractionalFoptdParams& params);

/// Exact unit-step response at time t_s after the step (closed form, Mittag-Leffler):
///   y(t) = K (1 - E_alpha(-(t - tau)^alpha / T))  for t > tau, 0 otherwise.
/// Independent of any simulator: use it as truth.  @throws std::invalid_argument (Validate).
double FractionalFoptdStepResponse(const FractionalFoptdParams& params, double t_s);

}  // namespace canalid::core
