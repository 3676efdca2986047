// The online three-step closed-loop method (OnlineThreeStep) against the batch FitIntegratorDelay's
// three-step branch on the Saint-Venant fixed-gate record of ASCE canal 2 pool 2, and its guards.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "core/integrator_delay/integrator_delay_model.h"
#include "core/online/online_integrator_delay.h"
#include "core/online/online_three_step.h"
#include "core/signal/detrend.h"
#include "pool_record.h"

namespace canalid::core {
namespace {

using testdata::PoolRecord;
using testdata::ReadPoolRecord;

double Rel(double a, double b) { return std::abs(a - b) / std::abs(b); }

constexpr int kMaxNk = 60;  // 3600 s at Ts = 60 s, as `canalid identify --max-delay-s 3600`

IntegratorDelayFit BatchThreeStep(const PoolRecord& r) {
  IntegratorDelayFitOptions o;
  o.max_nk = kMaxNk;
  o.closed_loop = ClosedLoopMode::kOn;
  return FitIntegratorDelay(r.q_in, r.q_out, r.level, r.ts, o);
}

// Step (3) against the batch's own numbers: FitIntegratorDelay's closed-loop branch fits the level
// on [cumsum(F_hat u_d), cumsum(free responses of F_hat), 1, k - k0] by QR, u_d the detrended
// delayed inflow.  Fed the batch's F_hat (IntegratorDelayFit::sensitivity_theta) and the same u_d,
// with lambda = 1, P0 = 1e10 I and no warm-up, the online regression must give the batch's b, c and
// d.  1e-6 relative, the issue's figure: the prior's I / P0 = 1e-10 is negligible against the
// information matrix (sum of Q_hat^2 of order 1e6 here).
TEST(OnlineThreeStep, FrozenBatchSensitivityEqualsBatchThreeStepRegression) {
  const PoolRecord r = ReadPoolRecord("asce2-pool2-prbs-fixed-gate.csv");
  const IntegratorDelayFit batch = BatchThreeStep(r);
  ASSERT_TRUE(batch.closed_loop);
  ASSERT_GE(batch.sensitivity_order, 1);
  const int nk = batch.model.nk;
  const int k0 = batch.first_sample;
  const auto rows = static_cast<int>(r.q_in.size()) - k0;
  const Eigen::VectorXd u_d = RemoveLinearTrend(r.q_in.segment(k0 - nk, rows)).detrended;

  ThreeStepOptions o;
  o.warmup_samples = 0;
  o.regression.initial_covariance = 1e10;
  OnlineThreeStep online(o);
  online.FreezeSensitivity(batch.sensitivity_order, batch.sensitivity_theta);
  for (int i = 0; i < rows; ++i) {
    // The measured total flow only feeds step (2), which is frozen here.
    online.Update(u_d(i), 0.0, r.level(k0 + i), true);
  }
  EXPECT_LT(Rel(online.b(), batch.model.b), 1e-6) << online.b() << " " << batch.model.b;
  EXPECT_LT(Rel(online.c_m(), batch.offset_m), 1e-6) << online.c_m() << " " << batch.offset_m;
  EXPECT_LT(Rel(online.d_m(), batch.drift_m_per_sample), 1e-6)
      << online.d_m() << " " << batch.drift_m_per_sample;
}

// The three-step estimate on the raw record (no detrending: it is causal) for one delay, from
// k0 = kMaxNk + 1 as the bank.
OnlineThreeStep RunAtDelay(const PoolRecord& r, int nk, const ThreeStepOptions& o = {}) {
  OnlineThreeStep online(o);
  for (int k = kMaxNk + 1; k < r.q_in.size(); ++k) {
    const double u = r.q_in(k - nk);
    online.Update(u, u - r.q_out(k - 1), r.level(k), true);
  }
  return online;
}

// The issue's held-out check for the three-step method alone, and how it depends on the delay:
// area within 20 % of 34113 m^2 (IDZ of ASCE canal 2 pool 2, Litrico and Fromion 2004) at the
// batch's delay (nk = 12, 720 s; true 682 s).  Observed on this record: 30635 m^2 at nk = 12
// (-10.2 %), 28316 m^2 at nk = 11 (-17.0 %); at nk = 13 the zero-DC-gain ARX never comes out
// stable (F_hat stays 0, so step 3 has no flow to fit and b stays 0).  The error at nk = 12 is
// the realization's, not a bias: over 12 realizations of the scenario (PRBS start state and
// sensor seed 1..12) it was -10.2 .. +11.2 % (mean +1.7 %, std 6.8 %; the record before the PRBS
// moved to core/signal/prbs gave +0.3 %), at nk = 11 -17.0 .. +2.1 % (mean -6.6 %).  So only the
// issue's 20 % is asserted, at nk = 12 and 11; nk = 13 is asserted to fail, which is what this
// record shows.
TEST(OnlineThreeStep, FixedGateRecordAreaByDelay) {
  const PoolRecord r = ReadPoolRecord("asce2-pool2-prbs-fixed-gate.csv");
  const double truth = 34113.0;
  const OnlineThreeStep at12 = RunAtDelay(r, 12);
  EXPECT_LT(Rel(r.ts / at12.b(), truth), 0.2) << r.ts / at12.b();
  const OnlineThreeStep at11 = RunAtDelay(r, 11);
  EXPECT_LT(Rel(r.ts / at11.b(), truth), 0.2) << r.ts / at11.b();
  const OnlineThreeStep at13 = RunAtDelay(r, 13);
  EXPECT_FALSE(Rel(r.ts / at13.b(), truth) < 0.2) << r.ts / at13.b();
  EXPECT_GT(at13.unstable_sensitivity_samples(), 700);
}

// The bank as `canalid identify --online --closed-loop three-step` runs it (nk 0..60, wave-front
// term in the IV bank that picks the delay, lambda 1), without p22: the issue's tolerance, area
// within 20 % of 34113 m^2 and delay within 0.5..1.2 x 682 s.  Observed: 720 s, 30635 m^2
// (-10.2 %, see above); the IV bank alone gives 39687 m^2 here (+16.3 %; 44215 m^2, +29.6 %, as
// `identify --online` runs it on the cleaned level up to 3600 s: the p22 g bias).
TEST(OnlineThreeStep, BankOnFixedGateRecordMeetsTheIssueTolerance) {
  const PoolRecord r = ReadPoolRecord("asce2-pool2-prbs-fixed-gate.csv");
  OnlineIntegratorDelayOptions o;
  o.sample_time_s = r.ts;
  o.max_delay_samples = kMaxNk;
  o.wave_front_term = true;
  o.closed_loop = ClosedLoopMode::kThreeStep;
  OnlineIntegratorDelayBank bank(o);
  for (Eigen::Index k = 0; k < r.q_in.size(); ++k) bank.Update(r.q_in(k), r.q_out(k), r.level(k));
  const IntegratorDelaySnapshot s = bank.Snapshot();
  ASSERT_TRUE(s.valid);
  EXPECT_TRUE(bank.health().closed_loop);
  EXPECT_GE(s.delay_s, 0.5 * 682.0);
  EXPECT_LE(s.delay_s, 1.2 * 682.0);
  EXPECT_LT(Rel(s.area_m2, 34113.0), 0.2) << s.area_m2 << " at " << s.delay_s << " s";
  EXPECT_EQ(s.wave_front_gain_s_per_m2, 0.0);
  EXPECT_TRUE(std::isfinite(s.area_std_m2));
}

// The batch three-step is as sensitive to the delay on this record (FitIntegratorDelay with min_nk
// = max_nk = nk, so k0 = nk + 1, a window 48..51 samples longer than the bank's): observed 29819
// m^2 at nk = 11 (-12.6 %), 32077 m^2 at 12 (-6.0 %), 52143 m^2 at 13 (+52.9 %, the sensitivity
// model falls back to order 1); over the 12 realizations above, at 12: -6.6 .. +8.2 %.  Asserted:
// the first two inside the issue's 20 %, the third outside it.
TEST(OnlineThreeStep, BatchThreeStepAreaByDelay) {
  const PoolRecord r = ReadPoolRecord("asce2-pool2-prbs-fixed-gate.csv");
  auto area = [&](int nk) {
    IntegratorDelayFitOptions o;
    o.min_nk = nk;
    o.max_nk = nk;
    o.closed_loop = ClosedLoopMode::kOn;
    return FitIntegratorDelay(r.q_in, r.q_out, r.level, r.ts, o).model.area_m2();
  };
  EXPECT_LT(Rel(area(11), 34113.0), 0.2) << area(11);
  EXPECT_LT(Rel(area(12), 34113.0), 0.2) << area(12);
  EXPECT_GT(Rel(area(13), 34113.0), 0.2) << area(13);
}

// A NaN or Inf level with level_ok = true is refused by step (3)'s Rls (nothing changes), i.e.
// the same as a sample given with level_ok = false; flows keep the simulation running either way.
TEST(OnlineThreeStep, NonFiniteLevelsLeaveTheFitUntouched) {
  const PoolRecord r = ReadPoolRecord("asce2-pool2-prbs-fixed-gate.csv");
  OnlineThreeStep a({});
  OnlineThreeStep b({});
  const double bad[] = {std::numeric_limits<double>::quiet_NaN(),
                        std::numeric_limits<double>::infinity()};
  for (int k = kMaxNk + 1; k < r.q_in.size(); ++k) {
    const double u = r.q_in(k - 12);
    const bool hit = k % 97 == 0;
    a.Update(u, u - r.q_out(k - 1), hit ? bad[k % 2] : r.level(k), true);
    b.Update(u, u - r.q_out(k - 1), r.level(k), !hit);
  }
  EXPECT_EQ(a.b(), b.b());
  EXPECT_EQ(a.c_m(), b.c_m());
  EXPECT_EQ(a.d_m(), b.d_m());
  EXPECT_GT(a.regression().health().rejected_invalid, 5);
}

// In the bank a bad flow is the last good one (so the integrators stay continuous): a NaN, an Inf
// and an absurd outflow give bit-identical snapshots to the record with those samples replaced by
// the previous outflow by hand; a bad level skips step 3 only.  Same samples, same snapshots.
TEST(OnlineThreeStep, BankReplacesBadFlowsAndIsDeterministic) {
  const PoolRecord r = ReadPoolRecord("asce2-pool2-prbs-fixed-gate.csv");
  OnlineIntegratorDelayOptions o;
  o.sample_time_s = r.ts;
  o.max_delay_samples = 20;
  o.wave_front_term = true;
  o.closed_loop = ClosedLoopMode::kThreeStep;
  OnlineIntegratorDelayBank corrupted(o);
  OnlineIntegratorDelayBank repaired(o);
  OnlineIntegratorDelayBank again(o);
  const double bad[] = {std::numeric_limits<double>::quiet_NaN(),
                        std::numeric_limits<double>::infinity(), 1e9};
  double last_good = r.q_out(0);
  int bad_count = 0;
  for (Eigen::Index k = 0; k < r.q_in.size(); ++k) {
    const bool hit = k > 0 && k % 101 == 0;
    const double q_out = hit ? bad[bad_count++ % 3] : r.q_out(k);
    if (!hit) last_good = r.q_out(k);
    corrupted.Update(r.q_in(k), q_out, r.level(k));
    repaired.Update(r.q_in(k), last_good, r.level(k));
    again.Update(r.q_in(k), q_out, r.level(k));
  }
  const IntegratorDelaySnapshot a = corrupted.Snapshot();
  const IntegratorDelaySnapshot b = repaired.Snapshot();
  const IntegratorDelaySnapshot c = again.Snapshot();
  ASSERT_TRUE(a.valid);
  EXPECT_EQ(a.b, b.b);
  EXPECT_EQ(a.c_m, b.c_m);
  EXPECT_EQ(a.delay_samples, b.delay_samples);
  EXPECT_EQ(corrupted.health().bad_flow_samples, bad_count);
  EXPECT_EQ(a.b, c.b);
  EXPECT_EQ(a.d_m, c.d_m);
  EXPECT_EQ(a.b_std, c.b_std);
}

// Closed forms, polynomials built from their roots: (1 - 0.7 z^-1)(1 - 0.8 z^-1) and
// (1 - 0.9 z^-1)^4 are stable; (1 - 2 z^-1)(1 - 0.5 z^-1), (1 - 1.1 z^-1)(1 - 0.5 z^-1)^3 (one root
// just outside) and a root on the unit circle are not.
TEST(OnlineThreeStep, StableAutoregressionClosedForms) {
  EXPECT_TRUE(StableAutoregression(Eigen::Vector4d(-1.5, 0.56, 0.0, 0.0), 2));
  EXPECT_FALSE(StableAutoregression(Eigen::Vector4d(-2.5, 1.0, 0.0, 0.0), 2));
  EXPECT_TRUE(StableAutoregression(Eigen::Vector4d(-3.6, 4.86, -2.916, 0.6561), 4));
  EXPECT_FALSE(StableAutoregression(Eigen::Vector4d(-1.0, 0.0, 0.0, 0.0), 1));
  EXPECT_TRUE(StableAutoregression(Eigen::Vector4d(-0.99, 0.0, 0.0, 0.0), 1));
  // (1 - 1.1 z^-1)(1 - 0.5 z^-1)^3: one root outside.
  EXPECT_FALSE(StableAutoregression(Eigen::Vector4d(-2.6, 2.4, -0.95, 0.1375), 4));
}

TEST(OnlineThreeStep, BadOptionsThrow) {
  ThreeStepOptions o;
  o.sensitivity_order = 5;
  EXPECT_THROW(OnlineThreeStep{o}, std::invalid_argument);
  o.sensitivity_order = 0;
  EXPECT_THROW(OnlineThreeStep{o}, std::invalid_argument);
  o = ThreeStepOptions{};
  o.warmup_samples = -1;
  EXPECT_THROW(OnlineThreeStep{o}, std::invalid_argument);
  OnlineThreeStep ok(ThreeStepOptions{});
  EXPECT_THROW(ok.FreezeSensitivity(2, Eigen::VectorXd::Zero(3)), std::invalid_argument);
  Eigen::VectorXd nan_theta = Eigen::VectorXd::Zero(4);
  nan_theta(1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ok.FreezeSensitivity(2, nan_theta), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
