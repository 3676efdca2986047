#include "core/numerics/cube_root.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace canalid::core {
namespace {

// Units in the last place between `value` and the correctly rounded `reference` (glibc's cbrt,
// which is correctly rounded on the ranges below, and cross-checked by cubing).
double UlpsFrom(double value, double reference) {
  const double ulp = std::nextafter(reference, std::numeric_limits<double>::infinity()) - reference;
  return std::abs(value - reference) / ulp;
}

TEST(CubeRoot, WithinFourUlpsOfLibmOverTheWholeFastRange) {
  std::mt19937_64 random(17);
  std::uniform_real_distribution<double> log2_x(-1000.0, 1000.0);
  double worst = 0.0;
  for (int k = 0; k < 2'000'000; ++k) {
    const double x = std::exp2(log2_x(random));
    worst = std::max(worst, UlpsFrom(CubeRoot(x), std::cbrt(x)));
  }
  EXPECT_LE(worst, 4.0);
}

TEST(CubeRoot, ExactCubesAndTheFrictionRange) {
  for (double r = 0.25; r <= 64.0; r += 0.25) {
    EXPECT_LE(UlpsFrom(CubeRoot(r * r * r), r), 4.0) << r;
  }
  // The friction argument P^4 / A^7 of canal sections: 1e-14 .. 1e2.
  for (double x = 1e-14; x < 1e2; x *= 1.0001) {
    const double y = CubeRoot(x);
    EXPECT_NEAR(y * y * y / x, 1.0, 1e-14) << x;
  }
}

TEST(CubeRoot, OutsideTheFastRangeIsLibms) {
  const double inf = std::numeric_limits<double>::infinity();
  for (const double x : {0.0, -0.0, -8.0, -1e-300, 1e-310, 0x1p-1001, 0x1p1001, 1e308, inf, -inf}) {
    EXPECT_EQ(CubeRoot(x), std::cbrt(x)) << x;
    EXPECT_EQ(std::signbit(CubeRoot(x)), std::signbit(std::cbrt(x))) << x;
  }
  EXPECT_TRUE(std::isnan(CubeRoot(std::numeric_limits<double>::quiet_NaN())));
}

}  // namespace
}  // namespace canalid::core
