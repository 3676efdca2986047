#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <vector>

#include "core/online_id.h"
#include "tests/core/online_test_data.h"

namespace canalid::core {
namespace {

// Closed-loop pool: a downstream gate sets q_out(k) = q0 + g (y_meas(k) - 2 m) from the measured
// level, an unmeasured offtake w(k)  disturbs the level, and
// y(k) - y(k-1) = b (q_in(k - nk) - q_out(k - 1) - w(k)), b = 60 / 6000, nk = 7, g = 3 m^2/s.
struct LoopData {
  std::vector<double> q_in;
  std::vector<double> q_out;
  std::vector<double> level;
};

// White offtake disturbance (std of a +-0.03 m^3/s random sign per sample).  Measured with this
// seed, area from IV / LS: white 0.03 -> 6171 / 6101; slow steps (clock 97) of 0.01 -> 14433 /
// 8691, of 0.1 -> 59996 / 150628: a persistent unmeasured disturbance integrates into a random walk
// that neither the integrated-flow LS nor this IV can separate (see
// OnlineIdOptions::closed_loop_iv).
constexpr double kDisturbance = 0.03;
constexpr int kClock = 1;

LoopData MakeLoop(int samples) {
  const double b = 0.01;
  const double g = 3.0;
  const std::vector<double> u = testdata::Prbs(samples, 8, 31);
  const std::vector<double> w = testdata::Prbs(samples, kClock, 37);
  testdata::TestRandom noise(41);
  LoopData d{std::vector<double>(static_cast<std::size_t>(samples)),
             std::vector<double>(static_cast<std::size_t>(samples)),
             std::vector<double>(static_cast<std::size_t>(samples))};
  double y = 2.0;
  for (int k = 0; k < samples; ++k) {
    const auto uk = static_cast<std::size_t>(k);
    d.q_in[uk] = 2.0 + 0.2 * u[uk];
    if (k >= 7) y += b * (d.q_in[uk - 7] - d.q_out[uk - 1] - kDisturbance * (w[uk]));
    d.level[uk] = y + 0.002 * noise.Normal();
    d.q_out[uk] = 2.0 + g * (d.level[uk] - 2.0);
  }
  return d;
}

OnlineIdOptions Options(bool iv) {
  OnlineIdOptions o;
  o.sample_time_s = 60.0;
  o.min_delay_samples = 7;
  o.max_delay_samples = 7;
  o.rls.initial_covariance = 1e8;
  o.closed_loop_iv = iv;
  return o;
}

// lambda = 1: the IV estimate equals the batch IV solution (Z' Phi)^-1 Z' y on the same rows
// (1e-6 relative; the 1e-8 prior is negligible) and the area is within 5 % (observed 2.8 %).
TEST(OnlineIdClosedLoop, InstrumentalVariableEqualsBatchIv) {
  const LoopData d = MakeLoop(4000);
  OnlineIdBank iv(Options(true));
  OnlineIdBank ls(Options(false));
  for (std::size_t k = 0; k < d.level.size(); ++k) {
    iv.Update(d.q_in[k], d.q_out[k], d.level[k]);
    ls.Update(d.q_in[k], d.q_out[k], d.level[k]);
  }
  const int k0 = 8;
  const int rows = static_cast<int>(d.level.size()) - k0;
  Eigen::MatrixXd phi(rows, 3);
  Eigen::MatrixXd z(rows, 3);
  Eigen::VectorXd y(rows);
  double q = 0.0;
  double qin = 0.0;
  for (int r = 0; r < rows; ++r) {
    const auto k = static_cast<std::size_t>(k0 + r);
    q += d.q_in[k - 7] - d.q_out[k - 1];
    qin += d.q_in[k - 7] - d.q_in[0];
    phi.row(r) << q, 1.0, r;
    z.row(r) << qin, 1.0, r;
    y(r) = d.level[k];
  }
  const Eigen::Vector3d batch = (z.transpose() * phi).lu().solve(z.transpose() * y);
  const IdSnapshot s_iv = iv.CandidateSnapshot(7);
  const IdSnapshot s_ls = ls.CandidateSnapshot(7);
  std::printf("area: iv %.1f, ls %.1f, truth 6000\n", s_iv.area_m2, s_ls.area_m2);
  EXPECT_LT(std::abs(s_iv.b - batch(0)) / std::abs(batch(0)), 1e-6);
  EXPECT_LT(std::abs(s_iv.c_m - batch(1)) / std::abs(batch(1)), 1e-6);
  EXPECT_LT(std::abs(s_iv.d_m - batch(2)) / std::abs(batch(2)), 1e-6);
  EXPECT_LT(std::abs(s_iv.area_m2 / 6000.0 - 1.0), 0.05);
}

}  // namespace
}  // namespace canalid::core
