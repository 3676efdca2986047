#pragma once
#include <Eigen/Core>

namespace canalid::core {

/// Solution of min ||X theta - y||^2 by column-pivoting Householder QR (never normal equations).
struct LeastSquaresSolution {
  Eigen::VectorXd theta;
  double residual_sum_of_squares = 0.0;
  int rank = 0;
};

/// @throws std::invalid_argument if rows differ or there are fewer rows than columns.
LeastSquaresSolution SolveLeastSquares(const Eigen::Ref<const Eigen::MatrixXd>& x,
                                       const Eigen::Ref<const Eigen::VectorXd>& y);

}  // namespace canalid::core
