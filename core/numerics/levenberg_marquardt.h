#pragma once
#include <Eigen/Core>
#include <functional>
#include <string>

namespace canalid::core {

/// Residual function r(p) for a least-squares problem min_p 0.5 ||r(p)||^2.  It writes into
/// `residuals` (already sized by the solver to the length it returned first) and returns false
/// when p is outside the function's domain (the step is then rejected).
using ResidualFunction =
    std::function<bool(const Eigen::VectorXd& params, Eigen::VectorXd& residuals)>;

struct LmOptions {
  int max_iterations = 200;
  double initial_lambda = 1e-3;            ///< Marquardt damping at start
  double relative_step_tolerance = 1e-10;  ///< stop when ||dp|| <= tol (||p|| + tol)
  double relative_cost_tolerance = 1e-12;  ///< stop when the cost decrease is below tol * cost
  double jacobian_step = 1e-6;  ///< relative finite-difference step (central differences)
};

struct LmResult {
  Eigen::VectorXd params;
  double cost = 0.0;  ///< 0.5 ||r||^2 at params
  int iterations = 0;
  int evaluations = 0;
  bool converged = false;
  std::string stop_reason;
};

/// Levenberg-Marquardt with Marquardt's diagonal scaling, a central-difference Jacobian and box
/// bounds enforced by projection (each trial point is clamped to [lower, upper]).  The linear
/// step is solved by QR of the augmented system [J; sqrt(lambda) D] (no normal equations).
/// @param lower, upper  same size as initial (use +-infinity for free parameters).
/// @throws std::invalid_argument if sizes disagree, the initial point is infeasible, or the
///         residual function rejects the initial point.
LmResult LevenbergMarquardt(const ResidualFunction& residual_function,
                            const Eigen::VectorXd& initial, const Eigen::VectorXd& lower,
                            const Eigen::VectorXd& upper, const LmOptions& options = {});

}  // namespace canalid::core
