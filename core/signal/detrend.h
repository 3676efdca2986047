#pragma once
#include <Eigen/Core>

namespace canalid::core {

/// Result of RemoveLinearTrend: detrended(k) = x(k) - (intercept + slope_per_sample * k),
/// k = 0..N-1 (the sample index; divide the slope by the sample time for a rate per second).
struct DetrendResult {
  Eigen::VectorXd detrended;
  double intercept = 0.0;         ///< fitted line at k = 0, unit of x
  double slope_per_sample = 0.0;  ///< unit of x per sample
};

/// Least-squares straight line through (k, x(k)), removed from x.  Solved with the centred index
/// (k - mean(k)), which makes the two normal directions orthogonal, so there is no
/// ill-conditioned 2x2 system however long the record.
/// @throws std::invalid_argument if x has fewer than 2 samples or non-finite values.
DetrendResult RemoveLinearTrend(const Eigen::Ref<const Eigen::VectorXd>& x);

/// Result of RemoveMean: centred = x - mean.
struct MeanRemovalResult {
  Eigen::VectorXd centred;
  double mean = 0.0;
};

/// @throws std::invalid_argument if x is empty or has non-finite values.
MeanRemovalResult RemoveMean(const Eigen::Ref<const Eigen::VectorXd>& x);

}  // namespace canalid::core
