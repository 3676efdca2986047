#pragma once

namespace canalid::sim {

/// Gains, limits and timing of a sampled PID that drives a flow (a pump) to hold a level.
struct LevelPidConfig {
  double setpoint_m = 0.0;
  double kp = 0.0;  ///< m^3/s per m of error.
  double ki = 0.0;  ///< m^3/s per m of error per s.
  double kd = 0.0;  ///< m^3/s per m/s of level change (derivative on the measurement).
  double min_flow_m3s = 0.0;
  double max_flow_m3s = 0.0;
  double sample_time_s = 0.0;
  /// true when more flow raises the held level (a pump filling the pool); false when it lowers
  /// it (the pool's own outflow pump).
  bool direct_action = true;
};

/// Discrete PID level controller of a pump, positional form, sampled every `sample_time_s` with
/// the output held in between (zero-order hold).  With the error e_k = s (setpoint - y_k), s = +1
/// for direct action and -1 for reverse action:
///   I_k = I_{k-1} + ki Ts e_k   (only while the output is not pushed further into a limit)
///   u_k = clamp(kp e_k + I_k - s kd (y_k - y_{k-1}) / Ts, min_flow, max_flow)
/// Anti-windup by conditional integration: a sample whose unclamped output lies beyond a limit
/// and whose error pushes it further that way leaves I unchanged, so the output leaves the limit
/// as soon as the error changes sign.  The derivative acts on the measurement, so a setpoint
/// change gives no kick.  I starts at the flow given to Reset, so the loop starts bumpless from a
/// steady state at its setpoint.  No allocation; not thread-safe.
class LevelPid final {
 public:
  /// @throws std::invalid_argument naming the field if a gain is negative or not finite, the
  /// limits are not min <= max (both finite, min >= 0), or sample_time_s is not > 0.
  explicit LevelPid(const LevelPidConfig& config);

  /// Starts from flow `flow_m3s` (clamped to the limits) with `level_m` as the previous sample.
  void Reset(double flow_m3s, double level_m);
  /// One sample: the new flow (m^3/s) for measured level `level_m`.
  double Update(double level_m);

  void SetSetpoint(double setpoint_m) { config_.setpoint_m = setpoint_m; }
  const LevelPidConfig& config() const { return config_; }
  double output_m3s() const { return output_; }
  double integral_m3s() const { return integral_; }
  /// true if the last Update clamped the output to a limit.
  bool saturated() const { return saturated_; }

 private:
  LevelPidConfig config_;
  double integral_ = 0.0;
  double previous_level_m_ = 0.0;
  double output_ = 0.0;
  bool saturated_ = false;
};

}  // namespace canalid::sim
