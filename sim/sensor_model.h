#pragma once
#include <cstdint>
#include <random>

namespace canalid::sim {

/// What a sensor does to the true value; all zero means a perfect sensor.  Rates are expected
/// events per hour (each sample starts one with probability rate * period / 3600).
struct SensorConfig {
  double noise_std = 0.0;         ///< Gaussian white noise standard deviation (signal units).
  double quantum = 0.0;           ///< resolution: readings are rounded to a multiple of it.
  double spike_rate_per_h = 0.0;  ///< single-sample outliers of random sign ...
  double spike_min = 0.0;         ///< ... with a magnitude uniform in [spike_min, spike_max].
  double spike_max = 0.0;
  double drift_per_h = 0.0;         ///< linear offset growing with time (signal units per hour).
  double stuck_rate_per_h = 0.0;    ///< episodes where the reading freezes at its last value ...
  double stuck_duration_s = 0.0;    ///< ... for this long.
  double dropout_rate_per_h = 0.0;  ///< episodes where the reading is missing (NaN) ...
  double dropout_duration_s = 0.0;  ///< ... for this long.
};

/// A seeded sensor: Read() maps the true value at time t to the reported one.  Order of effects:
/// drift, noise, spike, quantisation, then stuck (hold the last reading) or dropout (NaN).
/// Reproducible: the same seed and the same calls give the same readings.
class SensorModel final {
 public:
  SensorModel(const SensorConfig& config, std::uint64_t seed);
  /// @param period_s time between calls, for the event probabilities.
  double Read(double true_value, double time_s, double period_s);

 private:
  bool Happens(double rate_per_h, double period_s);
  SensorConfig config_;
  std::mt19937_64 rng_;
  double last_ = 0.0;
  bool have_last_ = false;
  double stuck_until_s_ = -1.0;
  double dropout_until_s_ = -1.0;
};

}  // namespace canalid::sim
