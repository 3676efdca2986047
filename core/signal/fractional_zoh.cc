#include "core/signal/fractional_zoh.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

namespace canalid::core {
namespace {

// [[e^{A t}, int_0^t e^{A s} ds B], [0, 1]].
Eigen::MatrixXd AugmentedExponential(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, double t) {
  const Eigen::Index n = a.rows();
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n + 1, n + 1);
  m.topLeftCorner(n, n) = a * t;
  m.topRightCorner(n, 1) = b * t;
  return m.exp();
}

}  // namespace

ZohSplitModel DiscretizeZohSplit(const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                                 double sample_time_s, double fraction) {
  const Eigen::Index n = a.rows();
  if (a.cols() != n || b.size() != n || n == 0) {
    throw std::invalid_argument("DiscretizeZohSplit: A must be square and B of matching size");
  }
  if (!(sample_time_s > 0.0) || !std::isfinite(sample_time_s)) {
    throw std::invalid_argument(
        "DiscretizeZohSplit: sample_time_s = " + std::to_string(sample_time_s) + " must be > 0");
  }
  if (!(fraction >= 0.0 && fraction < 1.0)) {
    throw std::invalid_argument("DiscretizeZohSplit: fraction = " + std::to_string(fraction) +
                                " must be in [0, 1)");
  }
  ZohSplitModel model;
  const Eigen::MatrixXd late = AugmentedExponential(a, b, (1.0 - fraction) * sample_time_s);
  model.gamma_current = late.topRightCorner(n, 1);
  if (fraction == 0.0) {
    model.phi = late.topLeftCorner(n, n);
    model.gamma_previous = Eigen::VectorXd::Zero(n);
    return model;
  }
  const Eigen::MatrixXd early = AugmentedExponential(a, b, fraction * sample_time_s);
  model.phi = late.topLeftCorner(n, n) * early.topLeftCorner(n, n);
  model.gamma_previous = late.topLeftCorner(n, n) * early.topRightCorner(n, 1);
  return model;
}

}  // namespace canalid::core
