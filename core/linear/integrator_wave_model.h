#pragma once
#include <Eigen/Core>

#include "core/numerics/metrics.h"

namespace canalid::core {

/// The LPV paper's integer reference model of a pool:
///   P(s) = k e^{-tau s} / (s (S s^2 + M s + 1)),
/// k in output units per (input unit x second), S in s^2, M in s (S > 0, M > 0: a stable
/// second-order factor; M^2 < 4 S gives the under-damped waves seen in the LPV paper's pilot).
struct IntegratorWaveModel {
  double gain = 1.0;        ///< k
  double s_coeff_s2 = 1.0;  ///< S
  double m_coeff_s = 1.0;   ///< M
  double delay_s = 0.0;     ///< tau >= 0
};

/// @throws std::invalid_argument naming the field, value and allowed range.
void Validate(const IntegratorWaveModel& model);

/// Exact ZOH simulation (states [v, v', integral of v], delayed ZOH split of fractional_delay.h,
/// matrix exponential), from rest: u[k] held over [k Ts, (k+1) Ts), y[k] at k Ts, u = 0 before
/// k = 0 (feed deviations).
/// @throws std::invalid_argument on an invalid model or sample_time_s <= 0.
Eigen::VectorXd SimulateIntegratorWave(const IntegratorWaveModel& model,
                                       const Eigen::Ref<const Eigen::VectorXd>& input,
                                       double sample_time_s);

struct IntegratorWaveFitOptions {
  double max_delay_s = 0.0;  ///< <= 0: min(record / 4, 100 Ts)
  int max_iterations = 100;
};

struct IntegratorWaveFit {
  IntegratorWaveModel model;
  FitMetrics metrics;
  Eigen::VectorXd simulated;   ///< model output, output offset added back
  double input_offset = 0.0;   ///< u[0]
  double output_offset = 0.0;  ///< rest level of y (least squares with k)
  bool converged = false;
};

/// Fit on the simulation error: a grid over tau (steps of max(Ts, max_delay / 40)), the natural
/// frequency (8 values, log-spaced between 10 / record and 1 / Ts rad/s) and damping (0.4, 0.8,
/// 1.5), then Levenberg-Marquardt on (log S, log M, tau); k and the rest level y0 by linear
/// least squares for each candidate.  Deviations from u[0].
/// @throws std::invalid_argument on sizes, fewer than 20 samples, sample_time_s <= 0 or an input
///         that never changes.
IntegratorWaveFit FitIntegratorWave(const Eigen::Ref<const Eigen::VectorXd>& input,
                                    const Eigen::Ref<const Eigen::VectorXd>& output,
                                    double sample_time_s,
                                    const IntegratorWaveFitOptions& options = {});

}  // namespace canalid::core
