#include "core/fractional/oustaloup.h"

#include <gtest/gtest.h>

#include <Eigen/LU>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>

#include "core/signal/fractional_delay.h"

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
  EXPECT_THROW(OustaloupApproximation(0.5, 1e-3, 1e3, kMaxOustaloupSections + 1),
               std::invalid_argument);
}

TEST(OustaloupTest, SectionsAreBoundedInDensityAndCount) {
  EXPECT_EQ(OustaloupSections(1e-3, 1e3, 2.0), 12);
  EXPECT_EQ(OustaloupSections(1.0, 1.5, 0.1), 1);  // at least one
  EXPECT_EQ(OustaloupSections(1e-5, 1e5, 20.0), 200);
  const auto message = [](double low, double high, double density) {
    try {
      OustaloupSections(low, high, density);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  // 1e9 per decade overflowed the int count (one section came out); 1000 made ~8000 sections.
  EXPECT_NE(message(3.97e-8, 5.0, 1e9)
                .find("sections_per_decade = 1000000000.000000 is out of "
                      "range (allowed: > 0 and <= 20)"),
            std::string::npos);
  EXPECT_NE(message(3.97e-8, 5.0, 1000.0).find("out of range"), std::string::npos);
  EXPECT_NE(message(1e-100, 1e100, 3.0).find("is out of range (allowed: 1..200)"),
            std::string::npos);
  EXPECT_NE(message(1e-300, 1e300, 3.0).find("Oustaloup sections = inf"), std::string::npos);
  EXPECT_NE(message(1e-3, 1e3, std::nan("")).find("sections_per_decade = nan"), std::string::npos);
  EXPECT_NE(message(1e3, 1e-3, 2.0).find("0 < low < high"), std::string::npos);
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
