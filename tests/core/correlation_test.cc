#include "core/linear/correlation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <utility>

#include "core/linear/arx.h"

namespace canalid::core {
namespace {

TEST(Correlation, NormalQuantilesMatchTables) {
  // Standard normal table values (Abramowitz & Stegun 26.2).
  EXPECT_NEAR(TwoSidedNormalQuantile(0.95), 1.959963985, 1e-8);
  EXPECT_NEAR(TwoSidedNormalQuantile(0.99), 2.575829304, 1e-8);
  EXPECT_NEAR(TwoSidedNormalQuantile(0.999), 3.290526731, 1e-8);
  EXPECT_THROW(TwoSidedNormalQuantile(1.0), std::invalid_argument);
  EXPECT_THROW(TwoSidedNormalQuantile(0.0), std::invalid_argument);
}

TEST(Correlation, FitArRecoversAKnownArProcess) {
  // x(t) - 1.3 x(t-1) + 0.4 x(t-2) = e(t) (poles 0.8 and 0.5), 20000 samples: LS estimates
  // have std ~ sqrt((1 - 0.4^2) / N) ~ 0.0065, so 0.03 is > 4 sigma.
  std::mt19937_64 rng(1);
  std::normal_distribution<double> e(0.0, 1.0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(20000);
  for (int t = 2; t < 20000; ++t) x(t) = 1.3 * x(t - 1) - 0.4 * x(t - 2) + e(rng);
  const Eigen::VectorXd c = FitAr(x, 2);
  EXPECT_NEAR(c(0), -1.3, 0.03);
  EXPECT_NEAR(c(1), 0.4, 0.03);
  // Filtering with C(q) must whiten: the lag-1 autocorrelation of the residual is ~0
  // (+-3/sqrt(N) = 0.021).
  const Eigen::VectorXd w = ApplyPolynomialFilter(c, x);
  EXPECT_EQ(w.size(), 19998);
  EXPECT_LT(std::abs(CrossCorrelation(w.head(19997), w.tail(19997), 0)(0)), 0.021);
  EXPECT_THROW(FitAr(x, 0), std::invalid_argument);
  EXPECT_THROW(FitAr(x.head(4), 2), std::invalid_argument);
}

// FitAr folds its QR a block of rows at a time; it must give the least-squares solution that
// FitArx (one QR of the whole regressor matrix, compared with Octave elsewhere) gives: on the AR
// process above, and on a slow PRBS-like series of long bits plus a little noise, whose lagged
// columns are nearly collinear (the prewhitening of an inflow record), over many blocks.
TEST(Correlation, FitArEqualsTheWholeMatrixLeastSquares) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> e(0.0, 1.0);
  Eigen::VectorXd ar = Eigen::VectorXd::Zero(20000);
  for (int t = 2; t < 20000; ++t) ar(t) = 1.3 * ar(t - 1) - 0.4 * ar(t - 2) + e(rng);
  Eigen::VectorXd slow(50000);
  std::bernoulli_distribution bit(0.5);
  double level = 0.0;
  for (Eigen::Index t = 0; t < slow.size(); ++t) {
    if (t % 341 == 0) level = bit(rng) ? 1.0 : -1.0;
    slow(t) = level + 1e-3 * e(rng);
  }
  for (const auto& [series, order] : {std::pair{ar, 2}, std::pair{ar, 10}, std::pair{slow, 10}}) {
    ArxOrders orders;
    orders.na = order;
    const Eigen::VectorXd whole = FitArx(series, Eigen::MatrixXd(series.size(), 0), orders).a;
    const Eigen::VectorXd blocked = FitAr(series, order);
    ASSERT_EQ(blocked.size(), order);
    EXPECT_LT((blocked - whole).norm(), 1e-9 * whole.norm()) << order << "\n"
                                                             << blocked << "\n"
                                                             << whole;
  }
  EXPECT_THROW(FitAr(Eigen::VectorXd::Constant(3000, 2.5), 3), std::invalid_argument);
}

TEST(Correlation, PolynomialFilterByHand) {
  Eigen::VectorXd x(5);
  x << 1, 2, 3, 4, 5;
  const Eigen::VectorXd w = ApplyPolynomialFilter(Eigen::Vector2d(-1.0, 0.5), x);
  // w(t) = x(t) - x(t-1) + 0.5 x(t-2) for t = 2..4
  EXPECT_EQ(w, Eigen::Vector3d(3 - 2 + 0.5, 4 - 3 + 1.0, 5 - 4 + 1.5));
}

TEST(Correlation, CrossCorrelationOfAShiftedCopyPeaksAtTheShift) {
  std::mt19937_64 rng(2);
  std::normal_distribution<double> e(0.0, 1.0);
  Eigen::VectorXd x(1000);
  for (double& v : x) v = e(rng);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(1000);
  y.tail(993) = 2.0 * x.head(993);  // y(t) = 2 x(t-7)
  const Eigen::VectorXd r = CrossCorrelation(x, y, 20);
  Eigen::Index peak = 0;
  r.maxCoeff(&peak);
  EXPECT_EQ(peak, 7);
  EXPECT_NEAR(r(7), 0.993, 0.01);  // 993 of 1000 products overlap
  // Hand value for a tiny case: x = [1 -1], y = [1 -1]: r(0) = 2 / 2 = 1, r(1) = -1 / 2.
  const Eigen::VectorXd small = CrossCorrelation(Eigen::Vector2d(1, -1), Eigen::Vector2d(1, -1), 1);
  EXPECT_DOUBLE_EQ(small(0), 1.0);
  EXPECT_DOUBLE_EQ(small(1), -0.5);
  EXPECT_THROW(CrossCorrelation(x, y.head(10), 1), std::invalid_argument);
  EXPECT_THROW(CrossCorrelation(x, Eigen::VectorXd::Ones(1000), 1), std::invalid_argument);
  EXPECT_THROW(CrossCorrelation(x, y, 1000), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
