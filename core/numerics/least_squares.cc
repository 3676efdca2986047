#include "core/numerics/least_squares.h"

#include <Eigen/QR>
#include <stdexcept>

namespace canalid::core {

LeastSquaresSolution SolveLeastSquares(const Eigen::Ref<const Eigen::MatrixXd>& x,
                                       const Eigen::Ref<const Eigen::VectorXd>& y) {
  if (x.rows() != y.size())
    throw std::invalid_argument("SolveLeastSquares: rows of X and y differ");
  if (x.rows() < x.cols())
    throw std::invalid_argument("SolveLeastSquares: fewer rows than unknowns");
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(x);
  LeastSquaresSolution s;
  s.theta = qr.solve(y);
  s.rank = static_cast<int>(qr.rank());
  s.residual_sum_of_squares = (x * s.theta - y).squaredNorm();
  return s;
}

OffsetGain FitOffsetGain(const Eigen::Ref<const Eigen::VectorXd>& s,
                         const Eigen::Ref<const Eigen::VectorXd>& y) {
  const double s_mean = s.mean();
  const double y_mean = y.mean();
  const double sxx = (s.array() - s_mean).square().sum();
  OffsetGain fit;
  fit.gain = sxx > 0.0 ? ((s.array() - s_mean) * (y.array() - y_mean)).sum() / sxx : 0.0;
  fit.offset = y_mean - fit.gain * s_mean;
  return fit;
}

}  // namespace canalid::core
