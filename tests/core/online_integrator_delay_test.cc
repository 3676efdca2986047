#include "core/online/online_integrator_delay.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "tests/core/online_test_data.h"
#include "tests/support/recentring_pair.h"

namespace canalid::core {
namespace {

using testdata::MakePool;
using testdata::PoolData;
using testdata::PoolSpec;

constexpr double kTs = 60.0;

// Independent batch solution: stack phi = [Q_nk(k), 1, k - k0] for k = k0..K-1 (rows whose level
// is usable) and solve by Householder QR.
Eigen::Vector3d BatchId(const PoolData& d, int nk, int max_nk, const std::vector<bool>& use) {
  const int k0 = max_nk + 1;
  const int n = static_cast<int>(d.level.size());
  std::vector<Eigen::Vector3d> rows;
  std::vector<double> ys;
  double q = 0.0;
  for (int k = k0; k < n; ++k) {
    q += d.q_in[static_cast<std::size_t>(k - nk)] - d.q_out[static_cast<std::size_t>(k - 1)];
    if (!use.empty() && !use[static_cast<std::size_t>(k)]) continue;
    rows.emplace_back(q, 1.0, k - k0);
    ys.push_back(d.level[static_cast<std::size_t>(k)]);
  }
  Eigen::MatrixXd a(static_cast<int>(rows.size()), 3);
  Eigen::VectorXd y(static_cast<int>(rows.size()));
  for (int i = 0; i < a.rows(); ++i) {
    a.row(i) = rows[static_cast<std::size_t>(i)].transpose();
    y(i) = ys[static_cast<std::size_t>(i)];
  }
  return a.householderQr().solve(y);
}

OnlineIntegratorDelayOptions BankOptions(int min_nk, int max_nk, double lambda) {
  OnlineIntegratorDelayOptions o;
  o.sample_time_s = kTs;
  o.min_delay_samples = min_nk;
  o.max_delay_samples = max_nk;
  o.rls.forgetting = lambda;
  o.rls.initial_covariance = 1e8;
  return o;
}

double Rel(double a, double b) { return std::abs(a - b) / std::abs(b); }

// With lambda = 1 and P0 = 1e8 I every candidate equals the batch QR solution.  The prior adds
// ||theta||^2 / P0 = O(1e-8) against an information matrix whose smallest eigenvalue is O(1e2)
// here, so 1e-6 relative (the tolerance) leaves four orders of margin.
TEST(OnlineIntegratorDelayBank, ForgettingOneEqualsBatchLeastSquaresForEveryDelay) {
  const PoolData d = MakePool(PoolSpec{});
  OnlineIntegratorDelayBank bank(BankOptions(0, 15, 1.0));
  for (std::size_t k = 0; k < d.level.size(); ++k) bank.Update(d.q_in[k], d.q_out[k], d.level[k]);
  for (int nk = 0; nk <= 15; ++nk) {
    const Eigen::Vector3d batch = BatchId(d, nk, 15, {});
    const IntegratorDelaySnapshot s = bank.CandidateSnapshot(nk);
    ASSERT_TRUE(s.valid);
    EXPECT_LT(Rel(s.b, batch(0)), 1e-6) << "nk " << nk;
    EXPECT_LT(Rel(s.c_m, batch(1)), 1e-6) << "nk " << nk;
    EXPECT_LT(Rel(s.d_m, batch(2)), 1e-6) << "nk " << nk;
  }
  // The selector finds the true delay; the area is within 3 standard deviations of the truth.
  const IntegratorDelaySnapshot s = bank.Snapshot();
  EXPECT_EQ(s.delay_samples, 7);
  EXPECT_DOUBLE_EQ(s.delay_s, 7 * kTs);
  EXPECT_LT(std::abs(s.area_m2 - 6000.0), 3.0 * s.area_std_m2)
      << s.area_m2 << " +- " << s.area_std_m2;
  EXPECT_LT(s.area_std_m2, 60.0);  // 1 % of the area
  // The drift is the unmeasured offtake: d = -b 0.02 m^3/s.
  EXPECT_NEAR(s.d_m, -0.01 * 0.02, 5.0 * s.d_std_m);
}

// Re-centring is an exact re-parameterisation: with forgetting 0.995 a bank that re-centres every
// 50 samples and one that never does agree to rounding (1e-9 relative on b).
TEST(OnlineIntegratorDelayBank, RecentringDoesNotChangeTheFit) {
  PoolSpec spec;
  spec.samples = 4000;
  const PoolData d = MakePool(spec);
  const OnlineIntegratorDelayOptions a = BankOptions(7, 7, 0.995);
  const canalid::testing::RecentringPair r = canalid::testing::RunWithAndWithoutRecentring(a, d, 7);
  const IntegratorDelaySnapshot& sa = r.recentred;
  const IntegratorDelaySnapshot& sb = r.plain;
  EXPECT_LT(Rel(sa.b, sb.b), 1e-9);
  EXPECT_LT(Rel(sa.c_m, sb.c_m), 1e-6);
  EXPECT_LT(Rel(sa.area_m2, 6000.0), 0.02);
}

// Bad levels skip the regression update only: the result equals batch least squares on the rows
// with a good level (flows still integrated).  Bad flows are replaced by the last good value.
TEST(OnlineIntegratorDelayBank, NanInfAndAbsurdSamplesAreRejected) {
  const PoolData d = MakePool(PoolSpec{});
  OnlineIntegratorDelayOptions o = BankOptions(5, 9, 1.0);
  o.level_abs_max_m = 100.0;
  OnlineIntegratorDelayBank bank(o);
  std::vector<bool> use(d.level.size(), true);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  int bad = 0;
  for (std::size_t k = 0; k < d.level.size(); ++k) {
    double y = d.level[k];
    if (k > 20 && k % 37 == 0) y = nan;
    if (k > 20 && k % 53 == 0) y = -inf;
    if (k > 20 && k % 71 == 0) y = 1e5;  // absurd
    if (!std::isfinite(y) || std::abs(y) > 100.0) {
      use[k] = false;
      ++bad;
    }
    bank.Update(d.q_in[k], d.q_out[k], y);
  }
  EXPECT_EQ(bank.health().bad_level_samples, bad);
  const Eigen::Vector3d batch = BatchId(d, 7, 9, use);
  const IntegratorDelaySnapshot s = bank.CandidateSnapshot(7);
  EXPECT_LT(Rel(s.b, batch(0)), 1e-6);
  EXPECT_LT(Rel(s.c_m, batch(1)), 1e-6);
  EXPECT_LT(Rel(s.d_m, batch(2)), 1e-6);

  // Flows: a NaN inflow is held at its last good value; the fit stays within 2 % of the area.
  OnlineIntegratorDelayBank bank2(o);
  for (std::size_t k = 0; k < d.level.size(); ++k) {
    const double qi = (k % 101 == 50) ? nan : d.q_in[k];
    const double qo = (k % 103 == 60) ? inf : d.q_out[k];
    bank2.Update(qi, qo, d.level[k]);
  }
  EXPECT_GT(bank2.health().bad_flow_samples, 50);
  const IntegratorDelaySnapshot s2 = bank2.CandidateSnapshot(7);
  EXPECT_TRUE(std::isfinite(s2.b) && std::isfinite(s2.c_m));
  EXPECT_LT(Rel(s2.area_m2, 6000.0), 0.02) << s2.area_m2;
  // A sample with nothing good before it is dropped, not counted as time.
  OnlineIntegratorDelayBank bank3(o);
  EXPECT_FALSE(bank3.Update(nan, 1.0, 1.0));
  EXPECT_EQ(bank3.health().dropped_samples, 1);
  EXPECT_EQ(bank3.health().samples, 0);
}

TEST(OnlineIntegratorDelayBank, SameSamplesGiveBitIdenticalSnapshots) {
  PoolSpec spec;
  spec.samples = 1500;
  const PoolData d = MakePool(spec);
  OnlineIntegratorDelayOptions o = BankOptions(0, 12, 0.99);
  o.rls.trace_max = 1.0;
  o.rls.huber = 3.0;
  OnlineIntegratorDelayBank a(o);
  OnlineIntegratorDelayBank b(o);
  for (std::size_t k = 0; k < d.level.size(); ++k) {
    a.Update(d.q_in[k], d.q_out[k], d.level[k]);
    b.Update(d.q_in[k], d.q_out[k], d.level[k]);
  }
  for (int nk = 0; nk <= 12; ++nk) {
    const IntegratorDelaySnapshot sa = a.CandidateSnapshot(nk);
    const IntegratorDelaySnapshot sb = b.CandidateSnapshot(nk);
    EXPECT_EQ(sa.b, sb.b);
    EXPECT_EQ(sa.c_m, sb.c_m);
    EXPECT_EQ(sa.d_m, sb.d_m);
    EXPECT_EQ(sa.b_std, sb.b_std);
    EXPECT_EQ(sa.loss, sb.loss);
    EXPECT_EQ(sa.health.trace_p, sb.health.trace_p);
  }
  EXPECT_EQ(a.selected_delay_samples(), b.selected_delay_samples());
}

// Windup: both flows held constant for 1000 samples = 20 memory lengths of lambda = 0.98 (the
// issue asks for ten), then excitation resumes.  Numbers observed with this seed (the assertions
// leave margin):
//   default (UD, directional forgetting): max area error 0.25 % while held, 0.26 % after;
//     trace(P) never exceeds its value at the end of the excitation (0.026);
//   plain exponential forgetting: trace(P) grows from 0.074 to 2.7e6 (lambda^-k), the area wanders
//     by 8 % while held and bursts to 83 % error when excitation resumes.
TEST(OnlineIntegratorDelayBank, DefaultMethodDoesNotWindUpWhenExcitationStops) {
  PoolSpec spec;
  spec.samples = 2600;
  spec.hold_from = 1000;
  spec.hold_to = 2000;
  const PoolData d = MakePool(spec);
  struct Run {
    double max_error_held = 0.0;
    double max_error_after = 0.0;
    double trace_before = 0.0;
    double max_trace_held = 0.0;
  };
  auto run = [&](RlsMethod method) {
    OnlineIntegratorDelayOptions o = BankOptions(7, 7, 0.98);
    o.rls.method = method;
    o.rls.initial_covariance = 1e4;
    OnlineIntegratorDelayBank bank(o);
    Run r;
    for (std::size_t k = 0; k < d.level.size(); ++k) {
      bank.Update(d.q_in[k], d.q_out[k], d.level[k]);
      const IntegratorDelaySnapshot s = bank.CandidateSnapshot(7);
      const double error = std::abs(s.area_m2 / 6000.0 - 1.0);
      if (k == 999) r.trace_before = s.health.trace_p;
      if (k >= 1000 && k < 2000) {
        r.max_error_held = std::max(r.max_error_held, error);
        r.max_trace_held = std::max(r.max_trace_held, s.health.trace_p);
      }
      if (k >= 2000) r.max_error_after = std::max(r.max_error_after, error);
    }
    return r;
  };
  const Run robust = run(RlsOptions{}.method);
  const Run plain = run(RlsMethod::kExponential);
  std::printf("default: held %.4f after %.4f trace %.3g -> %.3g\n", robust.max_error_held,
              robust.max_error_after, robust.trace_before, robust.max_trace_held);
  std::printf("exponential: held %.4f after %.4f trace %.3g -> %.3g\n", plain.max_error_held,
              plain.max_error_after, plain.trace_before, plain.max_trace_held);
  EXPECT_LT(robust.max_error_held, 0.01);
  EXPECT_LT(robust.max_error_after, 0.01);
  EXPECT_LE(robust.max_trace_held, 1.01 * robust.trace_before);
  EXPECT_GT(plain.max_trace_held, 1e4 * plain.trace_before);
  EXPECT_GT(plain.max_error_after, 0.2);
}

// Tracking with lambda = 0.98 and CUSUM resets (threshold 10): after a 20 % step in the backwater
// area (6000 -> 7200 m^2) the selected model is within 5 % of the new area with the right delay
// from 100 samples after the step on (observed: 59); after a change of delay 7 -> 10 samples the
// selection is 10 with the area within 5 % from 300 samples on (observed: 163).
int SamplesToSettle(const PoolSpec& spec, double area_after, int nk_after) {
  const PoolData d = MakePool(spec);
  OnlineIntegratorDelayOptions o = BankOptions(0, 15, 0.98);
  o.rls.initial_covariance = 1e4;
  o.rls.cusum_threshold = 10.0;
  OnlineIntegratorDelayBank bank(o);
  int last_bad = -1;
  const int change = std::max(spec.change_b_at, spec.change_nk_at);
  for (std::size_t k = 0; k < d.level.size(); ++k) {
    bank.Update(d.q_in[k], d.q_out[k], d.level[k]);
    const IntegratorDelaySnapshot s = bank.Snapshot();
    const bool settled =
        s.delay_samples == nk_after && std::abs(s.area_m2 / area_after - 1.0) < 0.05;
    if (static_cast<int>(k) >= change && !settled) last_bad = static_cast<int>(k);
  }
  return last_bad + 1 - change;
}

TEST(OnlineIntegratorDelayBank, TracksAreaStepAndDelayChange) {
  PoolSpec area_step;
  area_step.samples = 3000;
  area_step.change_b_at = 1500;
  area_step.b_after = area_step.b / 1.2;
  const int area_samples = SamplesToSettle(area_step, 7200.0, 7);
  PoolSpec delay_step;
  delay_step.samples = 3000;
  delay_step.change_nk_at = 1500;
  delay_step.nk_after = 10;
  const int delay_samples = SamplesToSettle(delay_step, 6000.0, 10);
  std::printf("settled after %d samples (area step), %d samples (delay change)\n", area_samples,
              delay_samples);
  EXPECT_LE(area_samples, 100);
  EXPECT_LE(delay_samples, 300);
}

TEST(OnlineIntegratorDelayBank, BadOptionsThrow) {
  OnlineIntegratorDelayOptions o;
  o.max_delay_samples = -1;
  EXPECT_THROW(OnlineIntegratorDelayBank{o}, std::invalid_argument);
  o = OnlineIntegratorDelayOptions{};
  o.sample_time_s = 0.0;
  EXPECT_THROW(OnlineIntegratorDelayBank{o}, std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
