#include "sim/backwater.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sim/saint_venant.h"
#include "tests/support/canal2_pool2.h"

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

using canalid::testing::Canal2Pool2;

TEST(SteadyProfile, MatchesRk4BackwaterOnCanal2Pool2) {
  const Pool p = Canal2Pool2();
  const std::vector<double> y = SteadyProfile(p, 10.0, 30, 2.1);
  ASSERT_EQ(y.size(), 31u);
  EXPECT_DOUBLE_EQ(y.back(), 2.1);
  // The trapezoidal standard step with dx = 100 m has an O(dx^2) error; 1 mm is well above it
  // and far below the 123 mm of backwater drawdown the profile has here.
  for (int j = 0; j <= 30; j += 5) {
    EXPECT_NEAR(y[static_cast<std::size_t>(j)], Rk4UpstreamDepth(p, 10.0, 2.1, 3000.0 - 100.0 * j),
                1e-3)
        << "node " << j;
  }
  EXPECT_LT(y.front(), 2.0);  // M2-like drawdown towards a normal depth below 2.1 m
}

// ASCE test canal 1 pool 2, the steep one (target depth left at its default).
Pool SteepCanal1Pool2() {
  Pool p;
  p.name = "c1p2";
  p.length_m = 1200;
  p.bottom_width_m = 1.0;
  p.side_slope = 1.5;
  p.bed_slope = 0.002;
  p.manning_n = 0.014;
  return p;
}

TEST(SteadyProfile, MatchesRk4OnSteepCanal1Pool2) {
  const Pool p = SteepCanal1Pool2();
  const std::vector<double> y = SteadyProfile(p, 1.8, 120, 0.9);
  // Steep pool: M1 backwater that reaches normal depth upstream; 10 m steps, 1 mm tolerance.
  for (int j = 0; j <= 120; j += 20) {
    EXPECT_NEAR(y[static_cast<std::size_t>(j)], Rk4UpstreamDepth(p, 1.8, 0.9, 1200.0 - 10.0 * j),
                1e-3)
        << "node " << j;
  }
}

// The Saint-Venant solver, started from the steady state at one flow and given another, must
// settle on the standard-step profile of the new flow through its own dynamics (the initial
// profile is the old flow's, so this is not the start-is-a-fixed-point property), and that profile
// on the RK4 backwater curve.  One pool with a free weir downstream, so the level settles.
struct SettleCase {
  Pool pool;
  double weir_width_m, flow_m3s, new_flow_m3s, max_dx_m, dt_s, duration_s;
};

TEST(SteadyProfile, SaintVenantSettlesOnTheStandardStepProfile) {
  Pool steep = SteepCanal1Pool2();
  steep.target_depth_m = 0.9;
  // Settling time constants A / (dQ/dh of the weir): about 2000 s on canal 2 pool 2, under
  // 200 s on canal 1 pool 2; the runs last 20 and 100 of them.
  const std::vector<SettleCase> cases = {{Canal2Pool2(), 7.0, 10.0, 11.0, 100.0, 30.0, 43200.0},
                                         {steep, 3.0, 1.8, 2.0, 10.0, 5.0, 18000.0}};
  for (const SettleCase& c : cases) {
    Canal canal;
    canal.name = c.pool.name;
    canal.pools = {c.pool};
    canal.pools[0].structure.type = Structure::Type::kWeir;
    canal.pools[0].structure.width_m = c.weir_width_m;
    canal.pools[0].structure.coefficient = 1.7;
    canal.upstream.flow_m3s = c.flow_m3s;
    canal.max_dx_m = c.max_dx_m;
    SaintVenantCanal plant(canal);
    const double y_up_before = plant.depth_m(0, 0);
    plant.SetUpstream(c.new_flow_m3s);
    for (double t = 0.0; t < c.duration_s; t += c.dt_s) plant.Step(c.dt_s);
    // Settled: the weir passes the inflow (a level still moving by 1e-6 m per time constant
    // would leave a flow mismatch of order 1e-8 of it).
    ASSERT_NEAR(plant.PoolOutflow(0), c.new_flow_m3s, 1e-6 * c.new_flow_m3s) << canal.name;
    const int cells = plant.num_nodes(0) - 1;
    const double y_down = plant.DownstreamDepth(0);
    const std::vector<double> profile = SteadyProfile(c.pool, c.new_flow_m3s, cells, y_down);
    double worst_step = 0.0, worst_rk4 = 0.0;
    for (int j = 0; j <= cells; ++j) {
      worst_step = std::max(worst_step,
                            std::abs(plant.depth_m(0, j) - profile[static_cast<std::size_t>(j)]));
      const double rk4 =
          Rk4UpstreamDepth(c.pool, c.new_flow_m3s, y_down, c.pool.length_m - plant.dx_m(0) * j);
      worst_rk4 = std::max(worst_rk4, std::abs(plant.depth_m(0, j) - rk4));
    }
    std::printf(
        "%s: settled at %.6f m downstream, %.4f m upstream; worst vs standard step %.2g m, "
        "vs RK4 %.2g m\n",
        canal.name.c_str(), y_down, plant.depth_m(0, 0), worst_step, worst_rk4);
    // The standard step solves the scheme's own steady equations, so what separates them is the
    // Newton tolerance (1e-10 m) and the last of the transient: 1e-6 m.  The RK4 curve is the
    // continuous backwater solution: 1 mm as in the tests above (O(dx^2) of the trapezoidal
    // step).  The profile moved: the upstream depth changed by centimetres with the flow.
    EXPECT_LT(worst_step, 1e-6) << canal.name;
    EXPECT_LT(worst_rk4, 1e-3) << canal.name;
    EXPECT_GT(std::abs(plant.depth_m(0, 0) - y_up_before), 0.02) << canal.name;
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
