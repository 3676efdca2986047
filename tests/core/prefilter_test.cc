#include "core/signal/prefilter.h"

#include <gtest/gtest.h>

#include <cmath>

namespace canalid::core {
namespace {

TEST(Prefilter, ImpulseResponseOfSecondOrderInverseA) {
  // A(z) = (1 - 0.7 z^-1)(1 - 0.5 z^-1) = 1 - 1.2 z^-1 + 0.35 z^-2; by partial fractions the
  // impulse response of 1/A is h(k) = (0.7^(k+1) - 0.5^(k+1)) / (0.7 - 0.5).
  const Eigen::Vector2d a(-1.2, 0.35);
  Eigen::VectorXd impulse = Eigen::VectorXd::Zero(60);
  impulse(0) = 1.0;
  const PrefilterResult r = PrefilterInverseA(a, impulse);
  for (int k = 0; k < 60; ++k) {
    const double h = (std::pow(0.7, k + 1) - std::pow(0.5, k + 1)) / 0.2;
    EXPECT_NEAR(r.filtered(k), h, 1e-13) << "k " << k;
  }
  EXPECT_EQ(r.a_polynomial, Eigen::Vector3d(1.0, -1.2, 0.35));
  EXPECT_NEAR(r.dc_gain, 1.0 / 0.15, 1e-12);
  // A held input settles at the DC gain.
  const PrefilterResult step = PrefilterInverseA(a, Eigen::VectorXd::Ones(200));
  EXPECT_NEAR(step.filtered(199), 1.0 / 0.15, 1e-12);
}

TEST(Prefilter, StabilityTestAgreesWithKnownRoots) {
  EXPECT_TRUE(IsStablePolynomial(Eigen::VectorXd()));
  EXPECT_TRUE(IsStablePolynomial(Eigen::Vector2d(-1.2, 0.35)));        // 0.7, 0.5
  EXPECT_FALSE(IsStablePolynomial(Eigen::Vector2d(-1.5, 0.5)));        // 1, 0.5 (marginal)
  EXPECT_FALSE(IsStablePolynomial(Eigen::VectorXd::Constant(1, -2)));  // 2
  EXPECT_TRUE(IsStablePolynomial(Eigen::Vector2d(-1.5, 0.7)));         // |p| = sqrt(0.7)
  EXPECT_FALSE(IsStablePolynomial(Eigen::Vector2d(-1.5, 1.1)));        // |p| = sqrt(1.1)
  // (1 - 0.9 z^-1)^3 = 1 - 2.7 z^-1 + 2.43 z^-2 - 0.729 z^-3 stable; (1 - 1.01 z^-1)^3 not.
  EXPECT_TRUE(IsStablePolynomial(Eigen::Vector3d(-2.7, 2.43, -0.729)));
  EXPECT_FALSE(
      IsStablePolynomial(Eigen::Vector3d(-3 * 1.01, 3 * 1.01 * 1.01, -1.01 * 1.01 * 1.01)));
}

TEST(Prefilter, RejectsUnstableA) {
  EXPECT_THROW(PrefilterInverseA(Eigen::Vector2d(-1.5, 0.5), Eigen::VectorXd::Ones(5)),
               std::invalid_argument);
  Eigen::VectorXd bad = Eigen::VectorXd::Ones(5);
  bad(1) = std::nan("");
  EXPECT_THROW(PrefilterInverseA(Eigen::Vector2d(-1.2, 0.35), bad), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
