#include "core/experiment/setpoint_limiter.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::core {

void ValidateSetpointLimits(const SetpointLimits& limits) {
  if (!std::isfinite(limits.min_value) || !std::isfinite(limits.max_value) ||
      limits.min_value > limits.max_value) {
    throw std::invalid_argument("setpoint limits: min_value = " + std::to_string(limits.min_value) +
                                " and max_value = " + std::to_string(limits.max_value) +
                                " must be finite with min_value <= max_value");
  }
  if (std::isnan(limits.max_rate_per_s) || limits.max_rate_per_s <= 0.0) {
    throw std::invalid_argument("setpoint limits: max_rate_per_s = " +
                                std::to_string(limits.max_rate_per_s) + " must be > 0");
  }
}

LimitedSetpoint LimitSetpoint(const SetpointLimits& limits, double requested, double previous,
                              double elapsed_s) {
  LimitedSetpoint out;
  if (!std::isfinite(requested)) {
    out.status = SetpointStatus::kNotFinite;
    return out;
  }
  const double clamped = std::clamp(requested, limits.min_value, limits.max_value);
  out.clamped = clamped != requested;
  // inf * 0 would be NaN when rate limiting is disabled and no time has passed.
  const double max_step = std::isinf(limits.max_rate_per_s)
                              ? limits.max_rate_per_s
                              : limits.max_rate_per_s * std::max(elapsed_s, 0.0);
  out.value = std::clamp(clamped, previous - max_step, previous + max_step);
  out.rate_limited = out.value != clamped;
  return out;
}

SetpointLimiter::SetpointLimiter(const SetpointLimits& limits) : limits_(limits) {
  ValidateSetpointLimits(limits);
}

void SetpointLimiter::Reset(double value, double time_s) {
  has_reference_ = true;
  reference_value_ = value;
  reference_time_s_ = time_s;
}

LimitedSetpoint SetpointLimiter::Apply(double requested, double time_s) const {
  if (!has_reference_) {
    LimitedSetpoint out;
    out.status = SetpointStatus::kNoReference;
    return out;
  }
  return LimitSetpoint(limits_, requested, reference_value_, time_s - reference_time_s_);
}

}  // namespace canalid::core
