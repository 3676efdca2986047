#pragma once
#include <Eigen/Core>

namespace canalid::core {

/// Exact zero-order-hold discretisation of x' = A x + B v with the delayed ZOH split (see
/// ZohDelaySplit): over one sample interval v = u_previous during the first fraction * Ts and
/// u_current afterwards, so
///   x[k+1] = phi x[k] + gamma_previous u_previous + gamma_current u_current,
///   phi = e^{A Ts},  gamma_current = int_0^{(1-f) Ts} e^{A s} ds B,
///   gamma_previous = e^{A (1-f) Ts} int_0^{f Ts} e^{A s} ds B.
/// Computed with the matrix exponential of the augmented matrix [[A, B], [0, 0]].
struct ZohSplitModel {
  Eigen::MatrixXd phi;
  Eigen::VectorXd gamma_previous;
  Eigen::VectorXd gamma_current;
};

/// @throws std::invalid_argument on size mismatch, sample_time_s <= 0 or fraction outside [0, 1).
ZohSplitModel DiscretizeZohSplit(const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                                 double sample_time_s, double fraction);

}  // namespace canalid::core
