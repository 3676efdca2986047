#include "core/signal/detrend.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <random>

namespace canalid::core {
namespace {

TEST(Detrend, RemovesAnExactLine) {
  const Eigen::VectorXd x = (3.0 + 0.25 * Eigen::ArrayXd::LinSpaced(1000, 0.0, 999.0)).matrix();
  const DetrendResult r = RemoveLinearTrend(x);
  EXPECT_NEAR(r.intercept, 3.0, 1e-12);
  EXPECT_NEAR(r.slope_per_sample, 0.25, 1e-15);
  EXPECT_LT(r.detrended.cwiseAbs().maxCoeff(), 1e-10);
}

TEST(Detrend, MatchesAnIndependentQrLineFit) {
  // Independent truth: Householder QR on [1, k] (a different algorithm from the centred form).
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.01);
  const Eigen::Index n = 86400;
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    x(k) = 1.7 - 2e-6 * static_cast<double>(k) + 0.05 * std::sin(0.001 * static_cast<double>(k)) +
           noise(rng);
  }
  Eigen::MatrixXd design(n, 2);
  design.col(0).setOnes();
  design.col(1) = Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1));
  const Eigen::Vector2d line = design.householderQr().solve(x);
  const DetrendResult r = RemoveLinearTrend(x);
  EXPECT_NEAR(r.intercept, line(0), 1e-10);
  EXPECT_NEAR(r.slope_per_sample, line(1), 1e-14);
  EXPECT_LT((r.detrended - (x - design * line)).cwiseAbs().maxCoeff(), 1e-10);
  // The residual of a least-squares line is orthogonal to both regressors.
  EXPECT_NEAR(r.detrended.sum(), 0.0, 1e-8);
  EXPECT_NEAR(r.detrended.dot(design.col(1)) / (n * n), 0.0, 1e-12);
}

TEST(Detrend, RemovesTheMean) {
  Eigen::VectorXd x(4);
  x << 1.0, 2.0, 3.0, 6.0;
  const MeanRemovalResult r = RemoveMean(x);
  EXPECT_DOUBLE_EQ(r.mean, 3.0);
  EXPECT_EQ(r.centred, Eigen::Vector4d(-2.0, -1.0, 0.0, 3.0));
}

TEST(Detrend, RejectsBadArguments) {
  EXPECT_THROW(RemoveLinearTrend(Eigen::VectorXd::Zero(1)), std::invalid_argument);
  EXPECT_THROW(RemoveMean(Eigen::VectorXd()), std::invalid_argument);
  Eigen::VectorXd bad = Eigen::VectorXd::Zero(5);
  bad(2) = std::nan("");
  EXPECT_THROW(RemoveLinearTrend(bad), std::invalid_argument);
  EXPECT_THROW(RemoveMean(bad), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
