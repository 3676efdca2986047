#include "core/integrator_delay/identify_idz.h"

namespace canalid::core {

IdzIdentification IdentifyIdz(const Eigen::Ref<const Eigen::VectorXd>& q_in,
                              const Eigen::Ref<const Eigen::VectorXd>& q_out,
                              const Eigen::Ref<const Eigen::VectorXd>& level, double sample_time_s,
                              const IdzIdentificationOptions& options) {
  IdzIdentification result;
  const Eigen::VectorXd clean_level = LevelWithoutSpikes(
      level, options.remove_level_outliers, options.level_outliers, &result.level_outliers);
  result.fit = FitIdz(q_in, q_out, clean_level, sample_time_s, options.fit);
  return result;
}

}  // namespace canalid::core
