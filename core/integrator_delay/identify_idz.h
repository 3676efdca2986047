#pragma once
#include <Eigen/Core>

#include "core/integrator_delay/identify_integrator_delay.h"
#include "core/integrator_delay/idz_fit.h"

namespace canalid::core {

/// Batch identification of a pool's IDZ model as `canalid identify --model idz` and the
/// daemon's end-of-experiment step do it: level spikes replaced as for the ID model
/// (LevelWithoutSpikes), then FitIdz.
struct IdzIdentificationOptions {
  IdzFitOptions fit;
  bool remove_level_outliers = true;
  HampelOptions level_outliers = IntegratorDelayIdentificationOptions{}.level_outliers;
};
struct IdzIdentification {
  IdzFit fit;
  OutlierReport level_outliers;
};
/// @throws std::invalid_argument as FitIdz.
IdzIdentification IdentifyIdz(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                              const Eigen::Ref<const Eigen::VectorXd>& q_out,
                              const Eigen::Ref<const Eigen::VectorXd>& level, double sample_time_s,
                              const IdzIdentificationOptions& options = {});

}  // namespace canalid::core
