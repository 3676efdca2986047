#include "core/oustaloup.h"

#include <gtest/gtest.h>

#include <Eigen/LU>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

#include "core/fractional_delay.h"

namespace canalid::core {
namespace {

std::complex<double> StateSpaceResponse(const OustaloupRealization& ss, double w) {
  const Eigen::Index n = ss.a.rows();
  const Eigen::MatrixXcd m = std::complex<double>(0.0, w) * Eigen::MatrixXcd::Identity(n, n) -
                             ss.a.cast<std::complex<double>>();
  const Eigen::VectorXcd x = m.partialPivLu().solve(ss.b.cast<std::complex<double>>());
  return (ss.c.cast<std::complex<double>>() * x)(0) + ss.d;
}

TEST(OustaloupTest, RealisationApproximatesFractionalPowerInsideTheBand) {
  // 3 sections per decade over 1e-3..1e3: gain within 1 % and phase within 1 degree
  // two decades inside the band edges (the edges bend the phase over more than a decade) (truth: (j
  // w)^gamma).
  for (double gamma : {-0.5, -0.2, 0.3, 0.7}) {
    const OustaloupFilter filter = OustaloupApproximation(gamma, 1e-3, 1e3, 18);
    const OustaloupRealization ss = RealizeOustaloup(filter);
    for (double w = 1e-1; w <= 1e1; w *= 1.7) {
      const std::complex<double> h = StateSpaceResponse(ss, w);
      EXPECT_NEAR(std::abs(h) / std::pow(w, gamma), 1.0, 1e-2) << "gamma " << gamma << " w " << w;
      EXPECT_NEAR(std::arg(h), gamma * std::numbers::pi / 2, 1.0 * std::numbers::pi / 180)
          << "gamma " << gamma << " w " << w;
    }
    // Band edges by construction: low^gamma at DC.
    EXPECT_NEAR(std::abs(StateSpaceResponse(ss, 1e-9)), std::pow(1e-3, gamma),
                1e-6 * std::pow(1e-3, gamma));
  }
}

TEST(OustaloupTest, RejectsBadArguments) {
  EXPECT_THROW(OustaloupApproximation(1.0, 1e-3, 1e3, 5), std::invalid_argument);
  EXPECT_THROW(OustaloupApproximation(0.5, 1e3, 1e-3, 5), std::invalid_argument);
  EXPECT_THROW(OustaloupApproximation(0.5, 1e-3, 1e3, 0), std::invalid_argument);
}

TEST(ZohDelaySplitTest, SplitsWholeAndFractionalSamples) {
  ZohDelaySplit s = SplitZohDelay(4.05, 0.15);
  EXPECT_EQ(s.whole_samples, 27);
  EXPECT_NEAR(s.fraction, 0.0, 1e-9);
  s = SplitZohDelay(0.4, 0.15);
  EXPECT_EQ(s.whole_samples, 2);
  EXPECT_NEAR(s.fraction, 0.4 / 0.15 - 2, 1e-12);
  EXPECT_THROW(SplitZohDelay(-1.0, 0.15), std::invalid_argument);
  ZohDelayLine line(2);
  for (int k = 0; k < 6; ++k) {
    line.Push(k);
    EXPECT_EQ(line.current(), k >= 2 ? k - 2 : 0);
    EXPECT_EQ(line.previous(), k >= 3 ? k - 3 : 0);
  }
}

}  // namespace
}  // namespace canalid::core
