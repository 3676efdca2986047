#pragma once
#include <Eigen/Core>
#include <vector>

namespace canalid::core {

/// Hampel identifier settings.
struct HampelOptions {
  /// Window of 2 * half_window + 1 samples centred on each sample (truncated at the ends), >= 1.
  int half_window = 15;
  /// A sample is an outlier when |x(i) - median| > threshold_sigma * sigma_i, > 0.
  double threshold_sigma = 5.0;
  /// Floor on sigma_i (same unit as x), >= 0.  With quantised sensors the MAD of a flat stretch
  /// can be 0 and then every one-step change would be flagged; set this to about one quantum.
  double min_sigma = 0.0;
  /// @throws std::invalid_argument naming the field, the value and the allowed range.
  void Validate() const;
};

/// What RemoveOutliers changed.
struct OutlierReport {
  std::vector<Eigen::Index> replaced;  ///< indices of the replaced samples, increasing
  Eigen::Index count = 0;              ///< replaced.size()
};

struct OutlierResult {
  Eigen::VectorXd cleaned;
  OutlierReport report;
};

/// Hampel filter: for each sample i, m_i = median of the window around i and
///   sigma_i = max(min_sigma, 1.4826 * median_j |x(j) - m_i|)   (MAD scaled to a Gaussian sigma);
/// i is flagged when |x(i) - m_i| > threshold_sigma * sigma_i.  Medians are computed on the raw
/// series.  Each flagged sample is replaced by linear interpolation between the nearest unflagged
/// neighbours on each side; flagged samples before the first (after the last) good sample take
/// its value.  O(N w) time with w the window length; allocates the result and one window buffer.
/// @throws std::invalid_argument on bad options, an empty or non-finite series.
OutlierResult RemoveOutliers(const Eigen::Ref<const Eigen::VectorXd>& x,
                             const HampelOptions& options = {});

}  // namespace canalid::core
