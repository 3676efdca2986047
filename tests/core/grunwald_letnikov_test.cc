#include "core/fractional/grunwald_letnikov.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace canalid::core {
namespace {

// Independent truth: (-1)^j binom(alpha, j) from the Gamma function.
double SignedBinomial(double alpha, int j) {
  const double binom = std::tgamma(alpha + 1) / (std::tgamma(j + 1.0) * std::tgamma(alpha - j + 1));
  return (j % 2 == 0) ? binom : -binom;
}

TEST(GrunwaldLetnikovTest, WeightsMatchSignedBinomials) {
  for (double alpha : {0.25, 0.5, 0.8, 1.3, 1.7}) {
    const Eigen::VectorXd w = GrunwaldLetnikovWeights(alpha, 15);
    for (int j = 0; j < 15; ++j) {
      // Gamma-ratio truth carries a few ulps of relative error per factor.
      EXPECT_NEAR(w(j), SignedBinomial(alpha, j), 1e-12 * std::max(1.0, std::abs(w(j))))
          << "alpha " << alpha << " j " << j;
    }
  }
}

TEST(GrunwaldLetnikovTest, IntegerOrdersGiveFiniteDifferences) {
  const Eigen::VectorXd w2 = GrunwaldLetnikovWeights(2.0, 6);
  const double expected[] = {1, -2, 1, 0, 0, 0};
  for (int j = 0; j < 6; ++j) EXPECT_DOUBLE_EQ(w2(j), expected[j]);
  EXPECT_EQ(GrunwaldLetnikovMemoryLength(1.0, 1e-9), 1);
  EXPECT_EQ(GrunwaldLetnikovMemoryLength(2.0, 1e-9), 2);
}

TEST(GrunwaldLetnikovTest, PartialSumIsTheCumulativeWeightSum) {
  for (double alpha : {0.3, 0.7, 1.4}) {
    const Eigen::VectorXd w = GrunwaldLetnikovWeights(alpha, 200);
    double cumulative = 0.0;
    for (int j = 0; j < 200; ++j) {
      cumulative += w(j);
      EXPECT_NEAR(GrunwaldLetnikovPartialSum(alpha, j), cumulative, 1e-13);
    }
  }
}

TEST(GrunwaldLetnikovTest, MemoryLengthMeetsToleranceWithoutGrossOversizing) {
  for (double alpha : {0.3, 0.6, 0.9, 1.2, 1.6}) {
    for (double tol : {1e-2, 1e-3, 1e-4}) {
      // alpha = 0.3 needs billions of terms below 1e-2: that is the clamped case below.
      if (alpha < 0.5 && tol < 1e-2) continue;
      const int length = GrunwaldLetnikovMemoryLength(alpha, tol);
      EXPECT_LE(std::abs(GrunwaldLetnikovPartialSum(alpha, length)), tol);
      // The asymptotic start plus doubling can overshoot by at most a factor 2 (+1 for ceil).
      EXPECT_GT(std::abs(GrunwaldLetnikovPartialSum(alpha, length / 2 - 1)), tol)
          << "alpha " << alpha << " tol " << tol << " L " << length;
    }
  }
  // Unreachable accuracy: clamped to max_length (L^-0.3 / Gamma(0.7) <= 1e-4 needs L ~ 1e13).
  EXPECT_EQ(GrunwaldLetnikovMemoryLength(0.3, 1e-4, 100000), 100000);
  // The tail bound itself: S(L) ~ L^-alpha / Gamma(1 - alpha) for large L (within 1 %).
  EXPECT_NEAR(GrunwaldLetnikovPartialSum(0.6, 100000) * std::tgamma(0.4) * std::pow(1e5, 0.6), 1.0,
              1e-2);
}

TEST(GrunwaldLetnikovTest, RejectsBadArguments) {
  EXPECT_THROW(GrunwaldLetnikovWeights(0.5, 0), std::invalid_argument);
  EXPECT_THROW(GrunwaldLetnikovMemoryLength(0.0, 1e-3), std::invalid_argument);
  EXPECT_THROW(GrunwaldLetnikovMemoryLength(0.5, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
