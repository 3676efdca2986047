#include "core/fractional/mittag_leffler.h"
#include "tests/support/frac_step_reference.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace canalid::core {
namespace {

// The accuracy the simulators' tests rely on.
constexpr double kTolerance = 1e-10;

TEST(MittagLefflerTest, OrderOneIsTheExponential) {
  for (double z = 0.0; z > -60.0; z -= 0.37) EXPECT_NEAR(MittagLeffler(1.0, z), std::exp(z), 1e-14);
}

TEST(MittagLefflerTest, OrderHalfIsScaledErfc) {
  // E_1/2(z) = exp(z^2) erfc(-z); both methods are exercised (series for |z| <= sqrt(15)).
  for (double z = -0.05; z > -25.0; z -= 0.113) {
    const double truth = std::exp(z * z) * std::erfc(-z);
    EXPECT_NEAR(MittagLeffler(0.5, z), truth, kTolerance) << "z " << z;
  }
}

TEST(MittagLefflerTest, MatchesTheLargeArgumentExpansion) {
  // E_a(-x) = sum_{k=1..} (-1)^(k+1) x^-k / Gamma(1 - a k) + exponentially small terms; at
  // x = 1e4 six terms leave an error below 1e-24.
  for (double alpha : {0.3, 0.6, 0.8, 0.95, 1.05, 1.3, 1.6}) {
    const double x = 1e4;
    double truth = 0.0;
    for (int k = 1; k <= 6; ++k) {
      const double arg = 1.0 - alpha * k;
      // 1/Gamma vanishes at non-positive integers.
      if (std::abs(arg - std::round(arg)) < 1e-12 && arg <= 0) continue;
      truth += ((k % 2 == 1) ? 1.0 : -1.0) * std::pow(x, -k) / std::tgamma(arg);
    }
    EXPECT_NEAR(MittagLeffler(alpha, -x), truth, 1e-13) << "alpha " << alpha;
  }
}

TEST(MittagLefflerTest, SeriesAndIntegralAgreeAtTheSwitch) {
  // The two methods are independent; t = (-z)^(1/alpha) = 15 is where they hand over.
  for (double alpha : {0.2, 0.45, 0.7, 0.9, 0.99, 1.01, 1.1, 1.4, 1.75, 1.9}) {
    const double z_switch = -std::pow(15.0, alpha);
    const double below = MittagLeffler(alpha, z_switch * (1 - 1e-12));
    const double above = MittagLeffler(alpha, z_switch * (1 + 1e-12));
    EXPECT_NEAR(below, above, kTolerance) << "alpha " << alpha;
  }
}

TEST(MittagLefflerTest, CompletelyMonotoneBelowOrderOne) {
  for (double alpha : {0.1, 0.5, 0.999}) {
    double previous = 1.0;
    for (double z = -0.01; z > -500.0; z *= 1.3) {
      const double e = MittagLeffler(alpha, z);
      EXPECT_GT(e, 0.0);
      EXPECT_LT(e, previous + 1e-15);
      previous = e;
    }
  }
}

TEST(MittagLefflerTest, ReproducesTheReferenceStepResponses) {
  int rows = 0;
  for (const auto& row : testing::ReadFracStepReference()) {
    const double y =
        row.gain *
        (1.0 - MittagLeffler(row.alpha, -std::pow(row.t_s, row.alpha) / row.time_constant_s));
    // The CSV carries 10 significant digits.
    EXPECT_NEAR(y, row.response, 1e-9) << "alpha " << row.alpha << " t " << row.t_s;
    ++rows;
  }
  EXPECT_EQ(rows, 16);
}

TEST(MittagLefflerTest, RejectsArgumentsOutsideTheDomain) {
  EXPECT_THROW(MittagLeffler(0.0, -1.0), std::invalid_argument);
  EXPECT_THROW(MittagLeffler(2.0, -1.0), std::invalid_argument);
  EXPECT_THROW(MittagLeffler(0.5, 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
