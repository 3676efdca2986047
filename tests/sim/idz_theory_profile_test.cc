// The IDZ theory approximates each pool's steady profile by a uniform part and a linear backwater
// part. Checked here against the simulator's own gradually varied profile (standard step method):
// the delay must be the travel time of a downstream wave, the integral of dx/(C + V) along the
// true profile.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <vector>

#include "core/hydraulics/idz_theory.h"
#include "sim/backwater.h"
#include "sim/canal_config.h"
#include "sim/hydraulics.h"

namespace canalid::sim {
namespace {

core::IdzTheory TheoryOf(const Pool& pool, double flow) {
  return core::IdzFromGeometry(
      core::PoolGeometry{pool.length_m, pool.bottom_width_m, pool.side_slope, pool.bed_slope,
                         pool.manning_n, pool.target_depth_m},
      flow);
}

double WaveTravelTime(const Pool& pool, double flow, int cells) {
  const std::vector<double> depth = SteadyProfile(pool, flow, cells, pool.target_depth_m);
  const TrapezoidSection section(pool.bottom_width_m, pool.side_slope, pool.manning_n);
  auto slowness = [&](double h) {
    const double a = section.Area(h);
    return 1.0 / (std::sqrt(kGravity * a / section.TopWidth(h)) + flow / a);
  };
  const double dx = pool.length_m / cells;
  double time = 0.0;
  for (int i = 0; i < cells; ++i) {
    time += 0.5 * dx *
            (slowness(depth[static_cast<std::size_t>(i)]) +
             slowness(depth[static_cast<std::size_t>(i) + 1]));
  }
  return time;
}

TEST(IdzTheoryProfile, DelayIsTheWaveTravelTimeOnTheSimulatorsProfile) {
  for (const char* file : {"/config/sim/asce-canal1.toml", "/config/sim/asce-canal2.toml"}) {
    const Canal canal = LoadCanal(std::string(CANALID_SOURCE_DIR) + file);
    const std::vector<double> flows = SteadyPoolFlows(canal);
    for (std::size_t i = 0; i < canal.pools.size(); ++i) {
      const Pool& pool = canal.pools[i];
      const double delay = TheoryOf(pool, flows[i]).model.delay_s;
      const double travel = WaveTravelTime(pool, flows[i], 2000);
      EXPECT_NEAR(delay / travel, 1.0, 0.01) << file << " pool " << pool.name << ": IDZ delay "
                                             << delay << " s, travel time " << travel << " s";
    }
  }
}

// The outflow's direct gain at low frequencies against the linearised equations integrated along
// the simulator's profile. The linearisation here is numerical (central differences of the
// nonlinear momentum terms), not the theory's algebra:
//   N(Q, Y, Q_x, Y_x) = 2 (Q/A) Q_x - (Q^2/A^2) T Y_x + g A Y_x + g A (Sf(Q, Y) - S0),
//   q_x = -T s y,   s q + N_Q q + N_Qx q_x + N_Y y + N_Yx y_x = 0.
struct LowFrequency {
  double area_m2;
  double outflow_gain_s_per_m2;
};

LowFrequency LinearisedAlongProfile(const Pool& pool, double flow, int cells, double delay_s) {
  const std::vector<double> depth = SteadyProfile(pool, flow, cells, pool.target_depth_m);
  const TrapezoidSection section(pool.bottom_width_m, pool.side_slope, pool.manning_n);
  const double dx = pool.length_m / cells;
  auto momentum = [&](double q, double y, double qx, double yx) {
    const double a = section.Area(y);
    return 2.0 * (q / a) * qx - (q * q / (a * a)) * section.TopWidth(y) * yx + kGravity * a * yx +
           kGravity * a * (section.FrictionSlope(y, q) - pool.bed_slope);
  };
  // d[q; y]/dx = F(x, s) [q; y] at a point of the profile (depth y, depth slope yx).
  auto rate = [&](double y, double yx, double s, double qy0, double qy1, double* d0, double* d1) {
    const double hq = 1e-6 * flow, hy = 1e-6 * y, hd = 1e-6;
    const double n_q = (momentum(flow + hq, y, 0, yx) - momentum(flow - hq, y, 0, yx)) / (2 * hq);
    const double n_y = (momentum(flow, y + hy, 0, yx) - momentum(flow, y - hy, 0, yx)) / (2 * hy);
    const double n_qx = (momentum(flow, y, hd, yx) - momentum(flow, y, -hd, yx)) / (2 * hd);
    const double n_yx = (momentum(flow, y, 0, yx + hd) - momentum(flow, y, 0, yx - hd)) / (2 * hd);
    const double t = section.TopWidth(y);
    *d0 = -t * s * qy1;
    *d1 = -((s + n_q) * qy0 + n_qx * (*d0) + n_y * qy1) / n_yx;
  };
  auto p22 = [&](double s) {
    // Two columns: start from q(0) = 0, y(0) = 1 (the response with no inflow).
    double q = 0.0, y = 1.0;
    for (int i = 0; i < cells; ++i) {
      const double y0 = depth[static_cast<std::size_t>(i)];
      const double y1 = depth[static_cast<std::size_t>(i) + 1];
      const double slope = (y1 - y0) / dx;
      const double ym = 0.5 * (y0 + y1);
      double k1q, k1y, k2q, k2y, k3q, k3y, k4q, k4y;
      rate(y0, slope, s, q, y, &k1q, &k1y);
      rate(ym, slope, s, q + 0.5 * dx * k1q, y + 0.5 * dx * k1y, &k2q, &k2y);
      rate(ym, slope, s, q + 0.5 * dx * k2q, y + 0.5 * dx * k2y, &k3q, &k3y);
      rate(y1, slope, s, q + dx * k3q, y + dx * k3y, &k4q, &k4y);
      q += dx / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
      y += dx / 6 * (k1y + 2 * k2y + 2 * k3y + k4y);
    }
    return y / q;
  };
  // p22(s) = -1/(A s) - c - e s at three low frequencies.
  const double e = 1e-4 / delay_s;
  double m[3][4];
  for (int i = 0; i < 3; ++i) {
    const double s = e * (i + 1);
    m[i][0] = -1.0 / s;
    m[i][1] = -1.0;
    m[i][2] = -s;
    m[i][3] = p22(s);
  }
  for (int c = 0; c < 3; ++c) {  // Gauss-Jordan, the matrix is well conditioned once scaled
    for (int r = 0; r < 3; ++r) {
      if (r == c) continue;
      const double f = m[r][c] / m[c][c];
      for (int k = 0; k < 4; ++k) m[r][k] -= f * m[c][k];
    }
  }
  return LowFrequency{m[0][0] / m[0][3], m[1][3] / m[1][1]};
}

// The theory's two-part profile is an approximation: on canal 2's long mild pools it is within
// 2.6 % (area, pool 1) and 5 % (low-frequency p22) of the true profile's linearised equations; on
// canal 1's short steep pools, whose backwater curve the straight line follows less well,
// within 8.8 % and 12.6 % (pool 1). Those measured figures set the two tolerances.
struct Tolerance {
  const char* file;
  double area;
  double gain;
};

TEST(IdzTheoryProfile, LowFrequencyGainsMatchTheLinearisedEquationsOnTheTrueProfile) {
  for (const Tolerance& tolerance : {Tolerance{"/config/sim/asce-canal1.toml", 0.10, 0.14},
                                     Tolerance{"/config/sim/asce-canal2.toml", 0.03, 0.06}}) {
    const char* file = tolerance.file;
    const Canal canal = LoadCanal(std::string(CANALID_SOURCE_DIR) + file);
    const std::vector<double> flows = SteadyPoolFlows(canal);
    for (std::size_t i = 0; i < canal.pools.size(); ++i) {
      const Pool& pool = canal.pools[i];
      const core::IdzTheory theory = TheoryOf(pool, flows[i]);
      const LowFrequency truth = LinearisedAlongProfile(pool, flows[i], 2000, theory.model.delay_s);
      std::cout << file << " pool " << pool.name << ": area " << theory.model.area_m2 << " vs "
                << truth.area_m2 << ", low-frequency p22 "
                << theory.outflow_gain_low_frequency_s_per_m2 << " vs "
                << truth.outflow_gain_s_per_m2 << "\n";
      EXPECT_NEAR(theory.model.area_m2 / truth.area_m2, 1.0, tolerance.area)
          << file << " pool " << pool.name;
      EXPECT_NEAR(theory.outflow_gain_low_frequency_s_per_m2 / truth.outflow_gain_s_per_m2, 1.0,
                  tolerance.gain)
          << file << " pool " << pool.name;
    }
  }
}

}  // namespace
}  // namespace canalid::sim
