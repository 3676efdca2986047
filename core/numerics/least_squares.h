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

/// y ~ offset + gain s by least squares: the gain and offset that fit a unit-gain response s best
/// (both enter every process model linearly, so the fits eliminate them this way).  Computed on
/// centred data; a constant s gives gain 0 and the mean of y.  @pre s.size() == y.size() > 0.
struct OffsetGain {
  double offset = 0.0;
  double gain = 0.0;
};
OffsetGain FitOffsetGain(const Eigen::Ref<const Eigen::VectorXd>& s,
                         const Eigen::Ref<const Eigen::VectorXd>& y);

}  // namespace canalid::core
