#pragma once
#include <Eigen/Core>

#include "core/integrator_delay/integrator_delay_model.h"
#include "core/linear/delay_estimation.h"
#include "core/signal/outliers.h"

namespace canalid::core {

struct IntegratorDelayIdentificationOptions {
  IntegratorDelayFitOptions fit;
  bool remove_level_outliers = true;
  /// Hampel settings for the level: 31-sample window, 5 sigma, sigma never below 5 mm, so only
  /// jumps above 2.5 cm are taken for spikes: with a floor of 1 mm the wave fronts of a
  /// gate-driven pool (a few mm per sample) were flagged, 16 samples on a clean 6.7 h record.
  HampelOptions level_outliers{15, 5.0, 0.005};
};

/// Batch identification of a pool's ID model as `canalid identify --model id` and the daemon's
/// end-of-experiment step do it (Ljung's loop, docs/references.md):
///   1. level spikes replaced by interpolation (Hampel), inflow and outflow untouched;
///   2. FitIntegratorDelay (delay scan, closed-loop detection, IV cross-check);
///   3. correlation analysis with prewhitening between the inflow and the level's first
///      difference (whose impulse response is b at lag nk) as a cross-check of the delay.
struct IntegratorDelayIdentification {
  IntegratorDelayFit fit;
  OutlierReport level_outliers;
  CorrelationDelayEstimate correlation;  ///< num_samples == 0 if the record was too short for it
};

/// Step 1 of both pipelines: the level with its spikes replaced (Hampel, `options`) when
/// `remove` and the level is finite, else the level as given; `report` says what was replaced.
Eigen::VectorXd LevelWithoutSpikes(const Eigen::Ref<const Eigen::VectorXd>& level, bool remove,
                                   const HampelOptions& options, OutlierReport* report);

/// @throws std::invalid_argument as FitIntegratorDelay.
IntegratorDelayIdentification IdentifyIntegratorDelay(
    const Eigen::Ref<const Eigen::VectorXd>& q_in, const Eigen::Ref<const Eigen::VectorXd>& q_out,
    const Eigen::Ref<const Eigen::VectorXd>& level, double sample_time_s,
    const IntegratorDelayIdentificationOptions& options = {});

}  // namespace canalid::core
