#include "core/numerics/levenberg_marquardt.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace canalid::core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(LevenbergMarquardt, SolvesRosenbrockToItsKnownMinimum) {
  // Rosenbrock as least squares: r = [10 (y - x^2), 1 - x]; the minimum is (1, 1) exactly.
  const ResidualFunction f = [](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    r.resize(2);
    r << 10.0 * (p(1) - p(0) * p(0)), 1.0 - p(0);
    return true;
  };
  const LmResult result = LevenbergMarquardt(
      f, Eigen::Vector2d(-1.2, 1.0), Eigen::Vector2d(-kInf, -kInf), Eigen::Vector2d(kInf, kInf));
  EXPECT_TRUE(result.converged) << result.stop_reason;
  EXPECT_NEAR(result.params(0), 1.0, 1e-6);
  EXPECT_NEAR(result.params(1), 1.0, 1e-6);
}

TEST(LevenbergMarquardt, FitsAnExponentialDecayExactly) {
  // y = 3 exp(-0.4 t): noise-free data, so the fit must recover the generating values.
  Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(50, 0.0, 10.0);
  Eigen::VectorXd y = 3.0 * (-0.4 * t.array()).exp();
  const ResidualFunction f = [&](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    r = (p(0) * (-p(1) * t.array()).exp()).matrix() - y;
    return true;
  };
  const LmResult result = LevenbergMarquardt(
      f, Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(kInf, kInf));
  EXPECT_NEAR(result.params(0), 3.0, 1e-8);
  EXPECT_NEAR(result.params(1), 0.4, 1e-8);
}

TEST(LevenbergMarquardt, KeepsParametersInsideTheirBounds) {
  // Unconstrained minimum at p = -2; with p >= 0 the answer is the bound.
  const ResidualFunction f = [](const Eigen::VectorXd& p, Eigen::VectorXd& r) {
    r.resize(1);
    r(0) = p(0) + 2.0;
    return true;
  };
  Eigen::VectorXd lower(1), upper(1), start(1);
  lower << 0.0;
  upper << 10.0;
  start << 5.0;
  const LmResult result = LevenbergMarquardt(f, start, lower, upper);
  EXPECT_DOUBLE_EQ(result.params(0), 0.0);
}

TEST(LevenbergMarquardt, RejectsAnInfeasibleStart) {
  const ResidualFunction f = [](const Eigen::VectorXd&, Eigen::VectorXd& r) {
    r = Eigen::VectorXd::Zero(1);
    return true;
  };
  Eigen::VectorXd lower(1), upper(1), start(1);
  lower << 0.0;
  upper << 1.0;
  start << 2.0;
  EXPECT_THROW(LevenbergMarquardt(f, start, lower, upper), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
