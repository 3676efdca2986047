#include "core/integrator_delay/identify_integrator_delay.h"

#include <algorithm>
#include <stdexcept>

#include "core/signal/detrend.h"

namespace canalid::core {

Eigen::VectorXd LevelWithoutSpikes(const Eigen::Ref<const Eigen::VectorXd>& level, bool remove,
                                   const HampelOptions& options, OutlierReport* report) {
  if (!remove || !level.allFinite() || level.size() == 0) return level;
  OutlierResult cleaned = RemoveOutliers(level, options);
  *report = std::move(cleaned.report);
  return std::move(cleaned.cleaned);
}

IntegratorDelayIdentification IdentifyIntegratorDelay(
    const Eigen::Ref<const Eigen::VectorXd>& q_in, const Eigen::Ref<const Eigen::VectorXd>& q_out,
    const Eigen::Ref<const Eigen::VectorXd>& level, double sample_time_s,
    const IntegratorDelayIdentificationOptions& options) {
  IntegratorDelayIdentification result;
  const Eigen::VectorXd clean_level = LevelWithoutSpikes(
      level, options.remove_level_outliers, options.level_outliers, &result.level_outliers);
  result.fit = FitIntegratorDelay(q_in, q_out, clean_level, sample_time_s, options.fit);

  // Cross-check of the delay.  It needs a few times the AR order of samples per lag examined.
  const Eigen::Index n = level.size();
  CorrelationDelayOptions correlation_options;
  correlation_options.max_lag = std::min<int>(result.fit.first_sample, static_cast<int>(n / 4));
  if (n >= 100 && correlation_options.max_lag >= 1) {
    const Eigen::VectorXd level_change = clean_level.tail(n - 1) - clean_level.head(n - 1);
    const Eigen::VectorXd inflow = q_in.tail(n - 1);
    try {
      result.correlation =
          EstimateDelayByCorrelation(RemoveLinearTrend(level_change).detrended,
                                     RemoveLinearTrend(inflow).detrended, correlation_options);
    } catch (const std::invalid_argument&) {
      // A cross-check only: a record it cannot use leaves it empty rather than failing the fit.
      result.correlation = CorrelationDelayEstimate{};
    }
  }
  return result;
}

}  // namespace canalid::core
