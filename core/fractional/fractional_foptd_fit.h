#pragma once
#include <Eigen/Core>

#include "core/fractional/fractional_foptd.h"
#include "core/fractional/fractional_simulator.h"
#include "core/numerics/metrics.h"

namespace canalid::core {

struct FractionalFoptdFitOptions {
  double alpha_min = 0.3;  ///< bounds on alpha, 0 < alpha_min < alpha_max < 2
  double alpha_max = 1.8;
  /// Upper bound on the delay [s]; <= 0 means half the record.
  double max_delay_s = 0.0;
  /// Joint Levenberg-Marquardt refinement of (T, alpha, tau) (K by least squares); false stops
  /// after the flume paper's staged fit (K from the final value, tau from the response start, T and
  /// alpha by ISE).
  bool refine = true;
  /// Oustaloup density used for the simulations inside the fit (2 keeps the model error below
  /// ~0.3 % of K at Ts = 0.15 s and a fit of 2,400 samples well under 0.2 s).
  double sections_per_decade = 2.0;  ///< (0, 20]
  int max_iterations = 60;
};

struct FractionalFoptdFitResult {
  FractionalFoptdParams params;   ///< the fitted model (gain, time_constant_s, alpha, delay_s)
  FractionalFoptdParams initial;  ///< the staged estimate before the joint refinement
  FitMetrics metrics;             ///< simulated vs measured output (metrics.h)
  Eigen::VectorXd simulated;      ///< model output in the units of y, offsets added back
  double input_offset = 0.0;      ///< u0 removed from the input
  double output_offset = 0.0;     ///< y0, the rest value of the output (refined by the fit)
  int simulations = 0;            ///< model simulations spent
  bool converged = false;         ///< LM stopped on a tolerance (or refine = false)
};

/// Fits the fractional FOPTD y ~ y0 + K e^{-tau s}/(1 + T s^alpha) (u - u0) to any record (a
/// gate step as in the flume paper, or PRBS-like input), sampled every sample_time_s with the
/// conventions of fractional_simulator.h (u[k] held over [k Ts, (k+1) Ts)). Deviations: u0 = u[0],
/// y0 = mean of y up to the first input change (at rest before it). Stages, as the flume paper does
/// them:
///  1. K from the final value (means of the last 5 % of du and dy) for a single step that ends
///     away from u0; otherwise (PRBS, pulses) by least squares in stage 3;
///  2. tau from the response start: the first of 5 consecutive samples whose centred 7-sample
///     mean of |dy| exceeds max(4 sigma / sqrt 7, 2 % of the final change) after the first input
///     change, sigma the noise level from the median absolute first difference; earlier
///     delays down to 0 are then scanned on the ISE (the detection lags for small steps);
///  3. T and alpha minimising the ISE (grid over alpha in 0.5..1.5 and the time scale
///     T^(1/alpha) in [Ts, record], with K re-estimated by least squares at each point);
///  4. joint LM refinement (core/numerics/levenberg_marquardt.h) of (log T^(1/alpha) bounded to
///     [Ts/100, 10 x record], alpha, tau) on the simulation
///     error, K and the rest value y0 eliminated by linear least squares for each (T, alpha,
///     tau) (so a record that starts at the step does not hang on its single rest sample).
/// Simulation uses the Oustaloup simulator (exact ZOH of the rational approximation, sub-sample
/// delay split), not GL1.
/// @throws std::invalid_argument if sizes differ, fewer than 20 samples, sample_time_s <= 0,
///         options out of range, or the input never changes.
FractionalFoptdFitResult FitFractionalFoptd(const Eigen::Ref<const Eigen::VectorXd>& input,
                                            const Eigen::Ref<const Eigen::VectorXd>& output,
                                            double sample_time_s,
                                            const FractionalFoptdFitOptions& options = {});

/// The Oustaloup band the fit simulates `params` with on a record of `samples` at
/// `sample_time_s`: DefaultOustaloupOptions over the record's length (samples x Ts; 0 samples
/// gives its 1000 Ts floor) at `options.sections_per_decade`.  `canalid identify` records it in
/// the model JSON; `canalid simulate` uses it for a model written without one.
/// @throws std::invalid_argument on invalid params or sample_time_s <= 0.
OustaloupOptions FitOustaloupBand(const FractionalFoptdParams& params, double sample_time_s,
                                  Eigen::Index samples,
                                  const FractionalFoptdFitOptions& options = {});

}  // namespace canalid::core
