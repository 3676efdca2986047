#pragma once
#include <Eigen/Core>

namespace canalid::core {

/// Goodness of a simulated output against the measured one (same length, same sampling).
///   rmse        sqrt(mean(e^2))                           e = y_sim - y
///   mae         mean(|e|)
///   fit_percent 100 (1 - ||e|| / ||y - mean(y)||)         (simulation, not one-step prediction)
///   ise         sum(e^2) * Ts
///   norm_error  sqrt(ise / t_f) / |dy|                     (the flume paper), t_f = N Ts
/// |dy| is the output change of the experiment: the mean of the last 5 % of the record minus the
/// mean of the first 5 % when that is at least half of the range max(y)-min(y) (a step
/// response); otherwise the range (a PRBS record).
struct FitMetrics {
  double rmse = 0.0;
  double mae = 0.0;
  double fit_percent = 0.0;
  double ise = 0.0;
  double norm_error = 0.0;
};

/// @throws std::invalid_argument when sizes differ, are empty, or sample_time_s <= 0.
FitMetrics ComputeMetrics(const Eigen::Ref<const Eigen::VectorXd>& measured,
                          const Eigen::Ref<const Eigen::VectorXd>& simulated, double sample_time_s);

/// The |dy| used by norm_error (see FitMetrics).
double OutputChange(const Eigen::Ref<const Eigen::VectorXd>& measured);

}  // namespace canalid::core
