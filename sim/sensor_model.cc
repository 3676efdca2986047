#include "sim/sensor_model.h"

#include <cmath>
#include <limits>

namespace canalid::sim {

SensorModel::SensorModel(const SensorConfig& config, std::uint64_t seed)
    : config_(config), rng_(seed) {}

bool SensorModel::Happens(double rate_per_h, double period_s) {
  if (rate_per_h <= 0.0) return false;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  return u(rng_) < rate_per_h * period_s / 3600.0;
}

double SensorModel::Read(double true_value, double time_s, double period_s) {
  // Draw every random number on every call so that switching one effect off does not reshuffle
  // the others for the same seed.
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double noise = normal(rng_);
  const bool spike = Happens(config_.spike_rate_per_h, period_s);
  const double spike_size = config_.spike_min + (config_.spike_max - config_.spike_min) * u(rng_);
  const double spike_sign = u(rng_) < 0.5 ? -1.0 : 1.0;
  const bool stuck = Happens(config_.stuck_rate_per_h, period_s);
  const bool dropout = Happens(config_.dropout_rate_per_h, period_s);

  double value = true_value + config_.drift_per_h * time_s / 3600.0 + config_.noise_std * noise;
  if (spike) value += spike_sign * spike_size;
  if (config_.quantum > 0.0) value = config_.quantum * std::round(value / config_.quantum);
  if (stuck && have_last_ && time_s >= stuck_until_s_) {
    stuck_until_s_ = time_s + config_.stuck_duration_s;
  }
  if (dropout && time_s >= dropout_until_s_) dropout_until_s_ = time_s + config_.dropout_duration_s;
  if (time_s < stuck_until_s_ && have_last_) value = last_;
  last_ = value;
  have_last_ = true;
  if (time_s < dropout_until_s_) return std::numeric_limits<double>::quiet_NaN();
  return value;
}

}  // namespace canalid::sim
