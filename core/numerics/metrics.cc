#include "core/numerics/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace canalid::core {

double OutputChange(const Eigen::Ref<const Eigen::VectorXd>& measured) {
  const Eigen::Index n = measured.size();
  if (n == 0) throw std::invalid_argument("OutputChange: empty record");
  const Eigen::Index window = std::max<Eigen::Index>(1, n / 20);
  const double first = measured.head(window).mean();
  const double last = measured.tail(window).mean();
  const double range = measured.maxCoeff() - measured.minCoeff();
  const double step = std::abs(last - first);
  return step >= 0.5 * range ? step : range;
}

FitMetrics ComputeMetrics(const Eigen::Ref<const Eigen::VectorXd>& measured,
                          const Eigen::Ref<const Eigen::VectorXd>& simulated,
                          double sample_time_s) {
  if (measured.size() == 0 || measured.size() != simulated.size()) {
    throw std::invalid_argument(
        "ComputeMetrics: measured and simulated must be non-empty and of equal size");
  }
  if (!(sample_time_s > 0.0))
    throw std::invalid_argument("ComputeMetrics: sample_time_s must be > 0");
  // The error as an expression, not a record-length vector: each sum reads both records again,
  // which costs less than the new vector's pages.
  const auto e = simulated - measured;
  const auto n = static_cast<double>(e.size());
  const double squared_error = e.squaredNorm();
  FitMetrics m;
  m.rmse = std::sqrt(squared_error / n);
  m.mae = e.cwiseAbs().mean();
  const double spread = (measured.array() - measured.mean()).matrix().norm();
  m.fit_percent = spread > 0.0 ? 100.0 * (1.0 - std::sqrt(squared_error) / spread) : 0.0;
  m.ise = squared_error * sample_time_s;
  const double dy = OutputChange(measured);
  const double t_f = n * sample_time_s;
  m.norm_error = dy > 0.0 ? std::sqrt(m.ise / t_f) / dy : std::numeric_limits<double>::infinity();
  return m;
}

}  // namespace canalid::core
