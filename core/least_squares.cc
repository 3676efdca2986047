#include "core/least_squares.h"

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

Eigen::Vector2d RemoveLine(Eigen::Ref<Eigen::VectorXd> values) {
  const Eigen::Index n = values.size();
  if (n < 2) throw std::invalid_argument("RemoveLine: needs at least 2 values");
  // Orthogonal basis {1, k - mean(k)} makes the projection two inner products.
  const double nd = static_cast<double>(n);
  const double k_mean = (nd - 1.0) / 2.0;
  const Eigen::ArrayXd centred = Eigen::ArrayXd::LinSpaced(n, 0.0, nd - 1.0) - k_mean;
  const double mean = values.mean();
  const double slope = (centred * values.array()).sum() / centred.square().sum();
  values.array() -= mean + slope * centred;
  return {mean - slope * k_mean, slope};
}

}  // namespace canalid::core
