#pragma once

namespace canalid::core {

/// Bounds on a setpoint written to the plant, in the channel's engineering unit (e.g. m for a
/// gate opening) and that unit per second.
struct SetpointLimits {
  double min_value = 0.0;
  double max_value = 0.0;
  double max_rate_per_s = 0.0;  ///< > 0; +infinity disables rate limiting
};

/// Throws std::invalid_argument naming the field when a bound is not finite, min_value >
/// max_value, or max_rate_per_s is NaN or <= 0.
void ValidateSetpointLimits(const SetpointLimits& limits);

enum class SetpointStatus {
  kOk,
  kNoReference,  ///< the limiter has no previous value to rate-limit from (Reset never called)
  kNotFinite,    ///< the requested value is NaN or infinite
};

struct LimitedSetpoint {
  double value = 0.0;  ///< what may be written (meaningful when status == kOk)
  SetpointStatus status = SetpointStatus::kOk;
  bool clamped = false;       ///< the request was outside [min_value, max_value]
  bool rate_limited = false;  ///< the step was cut to max_rate_per_s * elapsed_s
};

/// Clamp then rate-limit, pure:
///   c = clamp(requested, min_value, max_value)
///   value = clamp(c, previous - r dt, previous + r dt),   r = max_rate_per_s, dt = max(elapsed_s,
///   0)
/// The rate limit wins over the range: when `previous` lies outside the range the value moves
/// towards the range by at most r dt, never away from it.
LimitedSetpoint LimitSetpoint(const SetpointLimits& limits, double requested, double previous,
                              double elapsed_s);

/// The limiter state of one writable channel: the last value known to be in the plant and when.
/// Pure (time is passed in), not thread-safe, no allocation.
class SetpointLimiter final {
 public:
  /// @throws std::invalid_argument on bad limits (see ValidateSetpointLimits).
  explicit SetpointLimiter(const SetpointLimits& limits);

  /// Records that the plant holds `value` at `time_s` (after a successful write, or the first
  /// reading of the channel).
  void Reset(double value, double time_s);
  /// Drops the reference (e.g. after the link to the plant was lost, since the plant may have
  /// restarted with another value); Apply reports kNoReference until the next Reset.
  void Forget() { has_reference_ = false; }

  /// What may be written at `time_s` for `requested`; does not change the state (call Reset with
  /// the value once it has been written).
  LimitedSetpoint Apply(double requested, double time_s) const;

  bool has_reference() const { return has_reference_; }
  double reference_value() const { return reference_value_; }
  const SetpointLimits& limits() const { return limits_; }

 private:
  SetpointLimits limits_;
  bool has_reference_ = false;
  double reference_value_ = 0.0;
  double reference_time_s_ = 0.0;
};

}  // namespace canalid::core
