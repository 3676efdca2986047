#include "core/signal/outliers.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::core {
namespace {

// Median of v (reorders v).  Even sizes average the two middle values.
double Median(std::vector<double>& v) {
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double upper = v[mid];
  if (v.size() % 2 == 1) return upper;
  const double lower = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lower + upper);
}

constexpr double kMadToSigma = 1.4826;  // 1 / Phi^{-1}(3/4) for Gaussian data

}  // namespace

void HampelOptions::Validate() const {
  if (half_window < 1) {
    throw std::invalid_argument("HampelOptions.half_window = " + std::to_string(half_window) +
                                " must be >= 1");
  }
  if (!(threshold_sigma > 0.0) || !std::isfinite(threshold_sigma)) {
    throw std::invalid_argument("HampelOptions.threshold_sigma = " +
                                std::to_string(threshold_sigma) + " must be finite and > 0");
  }
  if (!(min_sigma >= 0.0) || !std::isfinite(min_sigma)) {
    throw std::invalid_argument("HampelOptions.min_sigma = " + std::to_string(min_sigma) +
                                " must be finite and >= 0");
  }
}

OutlierResult RemoveOutliers(const Eigen::Ref<const Eigen::VectorXd>& x,
                             const HampelOptions& options) {
  options.Validate();
  const Eigen::Index n = x.size();
  if (n == 0) throw std::invalid_argument("RemoveOutliers: the series is empty");
  if (!x.allFinite()) {
    throw std::invalid_argument("RemoveOutliers: the series contains NaN or infinite values");
  }
  OutlierResult result;
  std::vector<bool> flagged(static_cast<std::size_t>(n), false);
  std::vector<double> window;
  window.reserve(2 * static_cast<std::size_t>(options.half_window) + 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index lo = std::max<Eigen::Index>(0, i - options.half_window);
    const Eigen::Index hi = std::min<Eigen::Index>(n - 1, i + options.half_window);
    window.assign(x.data() + lo, x.data() + hi + 1);
    const double median = Median(window);
    for (double& v : window) v = std::abs(v - median);
    const double sigma = std::max(options.min_sigma, kMadToSigma * Median(window));
    if (std::abs(x(i) - median) > options.threshold_sigma * sigma) {
      flagged[static_cast<std::size_t>(i)] = true;
      result.report.replaced.push_back(i);
    }
  }
  result.report.count = static_cast<Eigen::Index>(result.report.replaced.size());
  result.cleaned = x;
  if (result.report.count == n) {
    throw std::invalid_argument(
        "RemoveOutliers: every sample was flagged; no good neighbour to interpolate from");
  }
  // Fill each run of flagged samples from its good neighbours.
  Eigen::Index i = 0;
  while (i < n) {
    if (!flagged[static_cast<std::size_t>(i)]) {
      ++i;
      continue;
    }
    Eigen::Index end = i;
    while (end < n && flagged[static_cast<std::size_t>(end)]) ++end;
    const Eigen::Index left = i - 1;  // good or -1
    const Eigen::Index right = end;   // good or n
    for (Eigen::Index k = i; k < end; ++k) {
      if (left < 0) {
        result.cleaned(k) = x(right);
      } else if (right >= n) {
        result.cleaned(k) = x(left);
      } else {
        const double w = static_cast<double>(k - left) / static_cast<double>(right - left);
        result.cleaned(k) = (1.0 - w) * x(left) + w * x(right);
      }
    }
    i = end;
  }
  return result;
}

}  // namespace canalid::core
