#include "core/numerics/levenberg_marquardt.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace canalid::core {
namespace {

Eigen::VectorXd Clamp(const Eigen::VectorXd& p, const Eigen::VectorXd& lower,
                      const Eigen::VectorXd& upper) {
  return p.cwiseMax(lower).cwiseMin(upper);
}

// Central differences, falling back to a one-sided difference at a bound or where the function
// rejects a probe point.
bool NumericJacobian(const ResidualFunction& f, const Eigen::VectorXd& p, const Eigen::VectorXd& r0,
                     const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, double rel_step,
                     Eigen::MatrixXd& jacobian, int& evaluations) {
  const Eigen::Index m = r0.size();
  jacobian.resize(m, p.size());
  Eigen::VectorXd r_plus(m);
  Eigen::VectorXd r_minus(m);
  for (Eigen::Index j = 0; j < p.size(); ++j) {
    const double h = rel_step * std::max(1.0, std::abs(p(j)));
    Eigen::VectorXd p_plus = p;
    Eigen::VectorXd p_minus = p;
    p_plus(j) = std::min(p(j) + h, upper(j));
    p_minus(j) = std::max(p(j) - h, lower(j));
    const bool ok_plus = p_plus(j) != p(j) && f(p_plus, r_plus);
    const bool ok_minus = p_minus(j) != p(j) && f(p_minus, r_minus);
    evaluations += 2;
    if (ok_plus && ok_minus) {
      jacobian.col(j) = (r_plus - r_minus) / (p_plus(j) - p_minus(j));
    } else if (ok_plus) {
      jacobian.col(j) = (r_plus - r0) / (p_plus(j) - p(j));
    } else if (ok_minus) {
      jacobian.col(j) = (r0 - r_minus) / (p(j) - p_minus(j));
    } else {
      return false;
    }
  }
  return true;
}

}  // namespace

LmResult LevenbergMarquardt(const ResidualFunction& residual_function,
                            const Eigen::VectorXd& initial, const Eigen::VectorXd& lower,
                            const Eigen::VectorXd& upper, const LmOptions& options) {
  const Eigen::Index n = initial.size();
  if (lower.size() != n || upper.size() != n || n == 0) {
    throw std::invalid_argument("LevenbergMarquardt: initial, lower and upper must have one size");
  }
  if ((initial.array() < lower.array()).any() || (initial.array() > upper.array()).any()) {
    throw std::invalid_argument("LevenbergMarquardt: initial point outside the bounds");
  }
  LmResult result;
  result.params = initial;
  Eigen::VectorXd r;
  if (!residual_function(result.params, r) || r.size() == 0 || !r.allFinite()) {
    throw std::invalid_argument(
        "LevenbergMarquardt: the residual function rejects the initial point");
  }
  result.evaluations = 1;
  result.cost = 0.5 * r.squaredNorm();
  const Eigen::Index m = r.size();

  double lambda = options.initial_lambda;
  Eigen::MatrixXd jacobian;
  Eigen::MatrixXd augmented(m + n, n);
  Eigen::VectorXd rhs(m + n);
  Eigen::VectorXd trial_r(m);
  Eigen::VectorXd scale = Eigen::VectorXd::Zero(n);

  for (result.iterations = 0; result.iterations < options.max_iterations; ++result.iterations) {
    if (!NumericJacobian(residual_function, result.params, r, lower, upper, options.jacobian_step,
                         jacobian, result.evaluations)) {
      result.stop_reason = "Jacobian could not be evaluated";
      return result;
    }
    // Marquardt scaling: the largest column norm seen so far keeps the damping scale-invariant.
    scale = scale.cwiseMax(jacobian.colwise().norm().transpose()).cwiseMax(1e-12);
    bool improved = false;
    while (lambda < 1e16) {
      augmented.topRows(m) = jacobian;
      augmented.bottomRows(n) = (std::sqrt(lambda) * scale).asDiagonal();
      rhs.head(m) = -r;
      rhs.tail(n).setZero();
      const Eigen::VectorXd step = augmented.colPivHouseholderQr().solve(rhs);
      const Eigen::VectorXd trial = Clamp(result.params + step, lower, upper);
      const double step_norm = (trial - result.params).norm();
      if (step_norm <= options.relative_step_tolerance *
                           (result.params.norm() + options.relative_step_tolerance)) {
        result.converged = true;
        result.stop_reason = "step below tolerance";
        return result;
      }
      ++result.evaluations;
      if (residual_function(trial, trial_r) && trial_r.allFinite()) {
        const double trial_cost = 0.5 * trial_r.squaredNorm();
        if (trial_cost < result.cost) {
          const double decrease = result.cost - trial_cost;
          result.params = trial;
          r = trial_r;
          result.cost = trial_cost;
          lambda = std::max(lambda / 10.0, 1e-12);
          improved = true;
          if (decrease <= options.relative_cost_tolerance * trial_cost) {
            result.converged = true;
            result.stop_reason = "cost decrease below tolerance";
            return result;
          }
          break;
        }
      }
      lambda *= 10.0;
    }
    if (!improved) {
      result.converged = true;
      result.stop_reason = "no further decrease (damping saturated)";
      return result;
    }
  }
  result.stop_reason = "iteration limit";
  return result;
}

}  // namespace canalid::core
