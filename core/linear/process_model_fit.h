#pragma once
#include <Eigen/Core>

#include "core/linear/process_models.h"
#include "core/numerics/metrics.h"

namespace canalid::core {

struct ProcessFitOptions {
  /// Largest delay searched, s.  <= 0 means a third of the record.
  double max_delay_s = 0.0;
};

/// The data are taken as deviations: the input from its first value, the output from a fitted
/// offset (the level the output would keep if the input never moved).
template <class Model>
struct ProcessFit {
  Model model;
  double output_offset = 0.0;  ///< y where u = u(0) at steady state
  double input_offset = 0.0;   ///< u(0)
  FitMetrics metrics;          ///< of the simulated output against the measured one
  Eigen::VectorXd simulated;   ///< absolute simulated output, same length as the data
  int iterations = 0;          ///< Levenberg-Marquardt iterations of the final refinement
};

using FoptdFit = ProcessFit<FoptdModel>;
using SoptdFit = ProcessFit<SoptdModel>;

/// Fits FOPTD to any input record (a step response or a richer input) by minimising the
/// simulation error (ISE).  The gain and the output offset enter linearly and are eliminated by
/// least squares for every (T, tau) tried (variable projection); (log T, tau) start from the best
/// point of a coarse grid and are refined by Levenberg-Marquardt, tau continuous (sub-sample).
/// @throws std::invalid_argument if sizes differ, there are fewer than 10 samples, Ts <= 0, or the
///         input never moves.
FoptdFit FitFoptd(const Eigen::Ref<const Eigen::VectorXd>& u,
                  const Eigen::Ref<const Eigen::VectorXd>& y, double sample_time_s,
                  const ProcessFitOptions& options = {});

/// Fits SOPTD the same way over (log T1, log T2, tau), starting from grids around the FOPTD fit;
/// the result has T1 >= T2.
SoptdFit FitSoptd(const Eigen::Ref<const Eigen::VectorXd>& u,
                  const Eigen::Ref<const Eigen::VectorXd>& y, double sample_time_s,
                  const ProcessFitOptions& options = {});

}  // namespace canalid::core
