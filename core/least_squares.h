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

/// Removes the least-squares line a + b k (k = 0..n-1) from `values`, in place, and returns
/// (a, b).  Exactly the projection onto the orthogonal complement of span{1, k}.
Eigen::Vector2d RemoveLine(Eigen::Ref<Eigen::VectorXd> values);

}  // namespace canalid::core
