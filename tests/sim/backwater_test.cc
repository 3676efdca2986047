#include "sim/backwater.h"

#include <gtest/gtest.h>

#include <cmath>

namespace canalid::sim {
namespace {

// Independent reference: dy/dx = (S0 - Sf)/(1 - Fr^2) integrated upstream with classical RK4
// on 0.5 m steps, with its own section formulas.
double Rk4UpstreamDepth(const Pool& p, double q, double y_down, double distance_m) {
  auto slope = [&](double y) {
    const double a = (p.bottom_width_m + p.side_slope * y) * y;
    const double t = p.bottom_width_m + 2 * p.side_slope * y;
    const double per = p.bottom_width_m + 2 * y * std::sqrt(1 + p.side_slope * p.side_slope);
    const double r = a / per;
    const double sf = p.manning_n * p.manning_n * q * q / (a * a * std::pow(r, 4.0 / 3.0));
    const double fr2 = q * q * t / (kGravity * a * a * a);
    return (p.bed_slope - sf) / (1 - fr2);
  };
  const double h = -0.5;  // integrate against x
  double y = y_down;
  for (double x = 0; x < distance_m - 1e-9; x += 0.5) {
    const double k1 = slope(y), k2 = slope(y + 0.5 * h * k1), k3 = slope(y + 0.5 * h * k2),
                 k4 = slope(y + h * k3);
    y += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  return y;
}

Pool Canal2Pool2() {
  Pool p;
  p.name = "2";
  p.length_m = 3000;
  p.bottom_width_m = 7;
  p.side_slope = 1.5;
  p.bed_slope = 1e-4;
  p.manning_n = 0.02;
  p.target_depth_m = 2.1;
  return p;
}

TEST(SteadyProfile, MatchesRk4BackwaterOnCanal2Pool2) {
  const Pool p = Canal2Pool2();
  const std::vector<double> y = SteadyProfile(p, 10.0, 30, 2.1);
  ASSERT_EQ(y.size(), 31u);
  EXPECT_DOUBLE_EQ(y.back(), 2.1);
  // The trapezoidal standard step with dx = 100 m has an O(dx^2) error; 1 mm is well above it
  // and far below the 123 mm of backwater drawdown the profile has here.
  for (int j = 0; j <= 30; j += 5) {
    EXPECT_NEAR(y[j], Rk4UpstreamDepth(p, 10.0, 2.1, 3000.0 - 100.0 * j), 1e-3) << "node " << j;
  }
  EXPECT_LT(y.front(), 2.0);  // M2-like drawdown towards a normal depth below 2.1 m
}

TEST(SteadyProfile, MatchesRk4OnSteepCanal1Pool2) {
  Pool p;
  p.name = "c1p2";
  p.length_m = 1200;
  p.bottom_width_m = 1.0;
  p.side_slope = 1.5;
  p.bed_slope = 0.002;
  p.manning_n = 0.014;
  const std::vector<double> y = SteadyProfile(p, 1.8, 120, 0.9);
  // Steep pool: M1 backwater that reaches normal depth upstream; 10 m steps, 1 mm tolerance.
  for (int j = 0; j <= 120; j += 20) {
    EXPECT_NEAR(y[j], Rk4UpstreamDepth(p, 1.8, 0.9, 1200.0 - 10.0 * j), 1e-3) << "node " << j;
  }
}

TEST(SteadyProfile, RejectsBadArguments) {
  const Pool p = Canal2Pool2();
  EXPECT_THROW(SteadyProfile(p, -1.0, 30, 2.1), std::invalid_argument);
  EXPECT_THROW(SteadyProfile(p, 10.0, 0, 2.1), std::invalid_argument);
  EXPECT_THROW(SteadyProfile(p, 10.0, 30, 0.0), std::invalid_argument);
  // Far more flow than the section carries subcritically at 0.3 m depth.
  EXPECT_THROW(SteadyProfile(p, 200.0, 30, 0.3), std::runtime_error);
}

}  // namespace
}  // namespace canalid::sim
