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
  double inflow_delay_s;  // tau of p21(s) = 1/(A s) - tau/A + O(s), the outflow held
};

// k of k[0] s^power[0] + k[1] s^power[1] + k[2] s^power[2] through three points (s, value), by
// Gauss-Jordan: the matrix is well conditioned once scaled.
struct ThreeTerms {
  double k[3];
};
ThreeTerms FitThreeTerms(const double (&s)[3], const double (&value)[3], const int (&power)[3]) {
  double m[3][4];
  for (int i = 0; i < 3; ++i) {
    for (int c = 0; c < 3; ++c) m[i][c] = std::pow(s[i], power[c]);
    m[i][3] = value[i];
  }
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) {
      if (r == c) continue;
      const double f = m[r][c] / m[c][c];
      for (int k = 0; k < 4; ++k) m[r][k] -= f * m[c][k];
    }
  }
  return ThreeTerms{{m[0][3] / m[0][0], m[1][3] / m[1][1], m[2][3] / m[2][2]}};
}

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
  // RK4 along the profile from one end to the other: [q(L); y(L)] from [q(0); y(0)], or back.
  auto propagate = [&](double s, bool backwards, double* q, double* y) {
    const double h = backwards ? -dx : dx;
    for (int j = 0; j < cells; ++j) {
      const int i = backwards ? cells - 1 - j : j;
      const double ya = depth[static_cast<std::size_t>(i)];
      const double yb = depth[static_cast<std::size_t>(i) + 1];
      const double slope = (yb - ya) / dx;
      const double y0 = backwards ? yb : ya, y1 = backwards ? ya : yb;
      const double ym = 0.5 * (y0 + y1);
      double k1q, k1y, k2q, k2y, k3q, k3y, k4q, k4y;
      rate(y0, slope, s, *q, *y, &k1q, &k1y);
      rate(ym, slope, s, *q + 0.5 * h * k1q, *y + 0.5 * h * k1y, &k2q, &k2y);
      rate(ym, slope, s, *q + 0.5 * h * k2q, *y + 0.5 * h * k2y, &k3q, &k3y);
      rate(y1, slope, s, *q + h * k3q, *y + h * k3y, &k4q, &k4y);
      *q += h / 6 * (k1q + 2 * k2q + 2 * k3q + k4q);
      *y += h / 6 * (k1y + 2 * k2y + 2 * k3y + k4y);
    }
  };
  // At three low frequencies: p22(s) = y(L)/q(L) from q(0) = 0, y(0) = 1, and p21(s) = y(L)/q(0)
  // from q(L) = 0, y(L) = 1 integrated back upstream (the mode that grows downstream in uniform
  // flow then decays, instead of cancelling between two forward solutions).
  const double e = 1e-4 / delay_s;
  double s[3], p21[3], p22[3];
  for (int i = 0; i < 3; ++i) {
    s[i] = e * (i + 1);
    double q = 0.0, y = 1.0;
    propagate(s[i], false, &q, &y);
    p22[i] = y / q;
    q = 0.0;
    y = 1.0;
    propagate(s[i], true, &q, &y);
    p21[i] = 1.0 / q;
  }
  // p22(s) = -1/(A s) - c - e s and p21(s) = 1/(A s) - tau/A + e' s.
  const ThreeTerms out = FitThreeTerms(s, p22, {-1, 0, 1});
  const ThreeTerms in = FitThreeTerms(s, p21, {-1, 0, 1});
  return LowFrequency{-1.0 / out.k[0], -out.k[1], -in.k[1] / in.k[0]};
}

// The theory's two-part profile is an approximation: on canal 2's long mild pools it is within
// 2.6 % (area, pool 1) and 5 % (low-frequency p22) of the true profile's linearised equations; on
// canal 1's short steep pools, whose backwater curve the straight line follows less well,
// within 8.8 % and 12.6 % (pool 1). The low-frequency delay is within 15.7 % of the pool's delay
// on canal 2 (pool 1, 1004 against 1253 s) and 18 % on canal 1 (pool 1, where it is -27 against
// -22 s of a 30 s delay); on canal 1's diffusive pools 2 and 5-8 within 3.4 %. Those measured
// figures set the three tolerances.
struct Tolerance {
  const char* file;
  double area;
  double gain;
  double delay;  // of the IDZ delay
};

TEST(IdzTheoryProfile, LowFrequencyGainsMatchTheLinearisedEquationsOnTheTrueProfile) {
  for (const Tolerance& tolerance : {Tolerance{"/config/sim/asce-canal1.toml", 0.10, 0.14, 0.2},
                                     Tolerance{"/config/sim/asce-canal2.toml", 0.03, 0.06, 0.17}}) {
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
                << truth.outflow_gain_s_per_m2 << ", low-frequency delay "
                << theory.delay_low_frequency_s << " vs " << truth.inflow_delay_s << " s\n";
      EXPECT_NEAR(theory.model.area_m2 / truth.area_m2, 1.0, tolerance.area)
          << file << " pool " << pool.name;
      EXPECT_NEAR(theory.outflow_gain_low_frequency_s_per_m2 / truth.outflow_gain_s_per_m2, 1.0,
                  tolerance.gain)
          << file << " pool " << pool.name;
      EXPECT_NEAR(theory.delay_low_frequency_s, truth.inflow_delay_s,
                  tolerance.delay * theory.model.delay_s)
          << file << " pool " << pool.name;
    }
  }
}

}  // namespace
}  // namespace canalid::sim
