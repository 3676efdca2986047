#include "core/linear/correlation.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::core {

Eigen::VectorXd FitAr(const Eigen::Ref<const Eigen::VectorXd>& x, int order) {
  if (order < 1) throw std::invalid_argument("FitAr: order " + std::to_string(order) + " < 1");
  if (x.size() <= 2 * Eigen::Index{order}) {
    throw std::invalid_argument("FitAr: " + std::to_string(x.size()) +
                                " samples are too few for order " + std::to_string(order) +
                                " (need more than " + std::to_string(2 * order) + ")");
  }
  // Rows t = p..N-1 of [-x(t-1) .. -x(t-p), x(t)], a block at a time, folded into the triangular
  // factor R of the whole matrix by a QR of [R; block] (TSQR): the least-squares solution of a
  // QR without the N x (p + 1) matrix (80 MB for an AR(10) over a million samples).
  const Eigen::Index p = order;
  const Eigen::Index width = p + 1;
  constexpr Eigen::Index kBlockRows = 1024;
  Eigen::MatrixXd stacked(width + kBlockRows, width);
  Eigen::MatrixXd r = Eigen::MatrixXd::Zero(width, width);
  Eigen::VectorXd squared_norms = Eigen::VectorXd::Zero(width);
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(width + kBlockRows, width);
  for (Eigen::Index t0 = p; t0 < x.size(); t0 += kBlockRows) {
    const Eigen::Index rows = std::min(kBlockRows, x.size() - t0);
    stacked.topRows(width) = r;
    auto block = stacked.middleRows(width, rows);
    for (Eigen::Index j = 1; j <= p; ++j) block.col(j - 1) = -x.segment(t0 - j, rows);
    block.col(p) = x.segment(t0, rows);
    squared_norms += block.colwise().squaredNorm().transpose();
    qr.compute(stacked.topRows(width + rows));
    r = qr.matrixQR().topRows(width).triangularView<Eigen::Upper>();
  }
  // R = [R11 r12; 0 r22]: c = R11^-1 r12.  A diagonal entry of R11 that vanishes against its
  // column's norm is a rank-deficient regressor (e.g. a constant series).
  for (Eigen::Index j = 0; j < p; ++j) {
    if (!(std::abs(r(j, j)) > 1e-10 * std::sqrt(squared_norms(j)))) {
      throw std::invalid_argument("FitAr: the lagged series are rank deficient at lag " +
                                  std::to_string(j + 1) + " (a constant or periodic series?)");
    }
  }
  return r.topLeftCorner(p, p).triangularView<Eigen::Upper>().solve(r.col(p).head(p));
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
