#include "core/signal/detrend.h"

#include <stdexcept>
#include <string>

namespace canalid::core {

DetrendResult RemoveLinearTrend(const Eigen::Ref<const Eigen::VectorXd>& x) {
  const Eigen::Index n = x.size();
  if (n < 2) {
    throw std::invalid_argument("RemoveLinearTrend: " + std::to_string(n) +
                                " samples; need at least 2");
  }
  if (!x.allFinite()) {
    throw std::invalid_argument("RemoveLinearTrend: the series contains NaN or infinite values");
  }
  const double k_mean = 0.5 * static_cast<double>(n - 1);
  const Eigen::ArrayXd k_centred =
      Eigen::ArrayXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)) - k_mean;
  const double x_mean = x.mean();
  DetrendResult result;
  result.slope_per_sample = (k_centred * (x.array() - x_mean)).sum() / k_centred.square().sum();
  result.intercept = x_mean - result.slope_per_sample * k_mean;
  result.detrended = (x.array() - x_mean - result.slope_per_sample * k_centred).matrix();
  return result;
}

MeanRemovalResult RemoveMean(const Eigen::Ref<const Eigen::VectorXd>& x) {
  if (x.size() == 0) throw std::invalid_argument("RemoveMean: the series is empty");
  if (!x.allFinite()) {
    throw std::invalid_argument("RemoveMean: the series contains NaN or infinite values");
  }
  MeanRemovalResult result;
  result.mean = x.mean();
  result.centred = x.array() - result.mean;
  return result;
}

}  // namespace canalid::core
