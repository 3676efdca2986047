#include "core/linear/correlation.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/linear/arx.h"

namespace canalid::core {

Eigen::VectorXd FitAr(const Eigen::Ref<const Eigen::VectorXd>& x, int order) {
  if (order < 1) throw std::invalid_argument("FitAr: order " + std::to_string(order) + " < 1");
  if (x.size() <= 2 * Eigen::Index{order}) {
    throw std::invalid_argument("FitAr: " + std::to_string(x.size()) +
                                " samples are too few for order " + std::to_string(order) +
                                " (need more than " + std::to_string(2 * order) + ")");
  }
  ArxOrders orders;
  orders.na = order;
  return FitArx(x, Eigen::MatrixXd(x.size(), 0), orders).a;
}

Eigen::VectorXd ApplyPolynomialFilter(const Eigen::Ref<const Eigen::VectorXd>& c,
                                      const Eigen::Ref<const Eigen::VectorXd>& x) {
  const Eigen::Index n = c.size();
  if (x.size() < n + 1) {
    throw std::invalid_argument("ApplyPolynomialFilter: " + std::to_string(x.size()) +
                                " samples for a filter of order " + std::to_string(n) +
                                "; need at least " + std::to_string(n + 1));
  }
  const Eigen::Index m = x.size() - n;
  Eigen::VectorXd w = x.tail(m);
  for (Eigen::Index j = 1; j <= n; ++j) w += c(j - 1) * x.segment(n - j, m);
  return w;
}

Eigen::VectorXd CrossCorrelation(const Eigen::Ref<const Eigen::VectorXd>& x,
                                 const Eigen::Ref<const Eigen::VectorXd>& y, int max_lag) {
  const Eigen::Index n = x.size();
  if (y.size() != n) {
    throw std::invalid_argument("CrossCorrelation: x has " + std::to_string(n) + " samples, y " +
                                std::to_string(y.size()));
  }
  if (max_lag < 0 || max_lag >= n) {
    throw std::invalid_argument("CrossCorrelation: max_lag " + std::to_string(max_lag) +
                                " must be in [0, " + std::to_string(n - 1) + "]");
  }
  const Eigen::VectorXd xc = x.array() - x.mean();
  const Eigen::VectorXd yc = y.array() - y.mean();
  const double scale = std::sqrt(xc.squaredNorm() * yc.squaredNorm());
  if (!(scale > 0.0)) {
    throw std::invalid_argument("CrossCorrelation: a series is constant; no correlation defined");
  }
  Eigen::VectorXd r(max_lag + 1);
  for (int k = 0; k <= max_lag; ++k) r(k) = xc.head(n - k).dot(yc.tail(n - k)) / scale;
  return r;
}

double TwoSidedNormalQuantile(double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("TwoSidedNormalQuantile: confidence " + std::to_string(confidence) +
                                " must be in (0, 1)");
  }
  // P(|Z| > z) = erfc(z / sqrt 2) decreases in z: bisect to the tail mass 1 - confidence.
  const double tail = 1.0 - confidence;
  double lo = 0.0;
  double hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (std::erfc(mid / std::sqrt(2.0)) > tail) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

}  // namespace canalid::core
