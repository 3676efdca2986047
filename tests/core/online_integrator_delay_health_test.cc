// The health flags of the online ID bank's snapshots (docs/lcm-channels.md, model_snapshot_t):
// each is set by an estimator state built for it, and a healthy estimator has none.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/online/online_integrator_delay.h"
#include "tests/core/online_test_data.h"

namespace canalid::core {
namespace {

using testdata::MakePool;
using testdata::PoolSpec;

OnlineIntegratorDelayOptions Options(int min_nk = 0, int max_nk = 15) {
  OnlineIntegratorDelayOptions o;
  o.sample_time_s = 60.0;
  o.min_delay_samples = min_nk;
  o.max_delay_samples = max_nk;
  return o;
}

// Runs the bank over the pool and returns the snapshot of candidate nk (or the selected one).
IntegratorDelaySnapshot RunBank(const OnlineIntegratorDelayOptions& o, const PoolSpec& spec,
                                int nk = -1, int samples = -1) {
  const testdata::PoolData d = MakePool(spec);
  OnlineIntegratorDelayBank bank(o);
  const std::size_t n = samples < 0 ? d.level.size() : static_cast<std::size_t>(samples);
  for (std::size_t k = 0; k < n; ++k) bank.Update(d.q_in[k], d.q_out[k], d.level[k]);
  return nk < 0 ? bank.Snapshot() : bank.CandidateSnapshot(nk);
}

// The default pool (A = 6000 m^2, nk = 7, PRBS in- and outflows) in a bank 0..15: measured
// condition number of P 1.6e7 (lambda 1) to 6e7 (lambda 0.98) after 3000 samples, smallest
// information 5e8 / p0.
TEST(OnlineIntegratorDelayHealth, AHealthyEstimatorHasNoFlag) {
  for (const double lambda : {1.0, 0.98}) {
    OnlineIntegratorDelayOptions o = Options();
    o.rls.forgetting = lambda;
    const IntegratorDelaySnapshot s = RunBank(o, PoolSpec{});
    ASSERT_TRUE(s.valid);
    EXPECT_EQ(s.delay_samples, 7);
    EXPECT_NEAR(s.area_m2, 6000.0, 60.0);
    EXPECT_EQ(s.flags, 0) << "lambda " << lambda;
    EXPECT_LT(s.condition_number, 1e8);
    EXPECT_GT(s.information_min * o.rls.initial_covariance, 1e6);
  }
}

// Flows that never move: Q_nk(k) = 0, so b gets no information at all (P keeps p0 along it).
TEST(OnlineIntegratorDelayHealth, LowExcitationWhenTheFlowsNeverMove) {
  PoolSpec spec;
  spec.q_in_amplitude_m3s = 0.0;
  spec.q_out_amplitude_m3s = 0.0;
  spec.offtake_m3s = 0.0;
  const OnlineIntegratorDelayOptions o = Options();
  const IntegratorDelaySnapshot s = RunBank(o, spec, 7);
  ASSERT_TRUE(s.valid);
  EXPECT_NEAR(s.information_min * o.rls.initial_covariance, 1.0, 1e-6);
  EXPECT_TRUE(s.flags & kFlagLowExcitation) << s.flags;
}

// A constant net inflow (0.05 m^3/s) with a PRBS of 0.2 l/s on top: Q_nk is almost k times a
// constant, collinear with the drift column.  Measured condition number 1e10 against 1.6e7
// for the healthy pool; the weakest direction still has 4e3 times the prior's information, so
// this is conditioning, not missing information.  (The PRBS swings the level by about 1e-5 m,
// under the level-resolution rule's 1e-4 m, which would set kFlagLowExcitation: that rule is off
// here.)
TEST(OnlineIntegratorDelayHealth, IllConditionedWhenTheRegressorsAreNearlyCollinear) {
  PoolSpec spec;
  spec.q_in_amplitude_m3s = 2e-4;
  spec.q_out_amplitude_m3s = 0.0;
  spec.offtake_m3s = -0.05;
  OnlineIntegratorDelayOptions o = Options();
  o.health.condition_max = 1e9;
  o.health.level_resolution_m = 0.0;
  const IntegratorDelaySnapshot s = RunBank(o, spec, 7, 500);
  ASSERT_TRUE(s.valid);
  EXPECT_GT(s.condition_number, 1e9);
  EXPECT_TRUE(s.flags & kFlagIllConditioned) << s.flags;
  EXPECT_FALSE(s.flags & kFlagLowExcitation) << s.flags;
  // The healthy pool under the same threshold is not flagged.
  EXPECT_FALSE(RunBank(o, PoolSpec{}, 7).flags & kFlagIllConditioned);
}

TEST(OnlineIntegratorDelayHealth, IllConditionedAtTheDefaultThresholdWhenPIsNearlySingular) {
  PoolSpec spec;
  spec.q_in_amplitude_m3s = 0.0;
  spec.q_out_amplitude_m3s = 0.0;
  spec.offtake_m3s = 0.0;
  const IntegratorDelaySnapshot s = RunBank(Options(), spec, 7);
  EXPECT_GT(s.condition_number, 1e12);
  EXPECT_TRUE(s.flags & kFlagIllConditioned) << s.flags;
}

// Exponential forgetting (lambda 0.98) with the flows held still from sample 500 on: P grows by
// 1 / lambda per sample along the unexcited directions, past n p0.
TEST(OnlineIntegratorDelayHealth, WindupWhenExponentialForgettingRunsWithoutExcitation) {
  PoolSpec spec;
  spec.hold_from = 500;
  spec.hold_to = 3000;
  OnlineIntegratorDelayOptions o = Options();
  o.rls.method = RlsMethod::kExponential;
  o.rls.forgetting = 0.98;
  EXPECT_EQ(RunBank(o, spec, 7, 500).flags, 0);
  const IntegratorDelaySnapshot s = RunBank(o, spec, 7, 2000);
  EXPECT_GT(s.health.trace_p, 3.0 * o.rls.initial_covariance);
  EXPECT_TRUE(s.flags & kFlagWindup) << s.flags;
}

// excitation_min 0.01: the first samples (phi' P phi large) update, later ones (measured r about
// 0.004 after 1000 samples) carry too little information and freeze the estimator.
TEST(OnlineIntegratorDelayHealth, FrozenWhenTheLastSampleCarriedNoInformation) {
  OnlineIntegratorDelayOptions o = Options();
  o.rls.excitation_min = 0.01;
  const IntegratorDelaySnapshot s = RunBank(o, PoolSpec{}, 7);
  ASSERT_TRUE(s.valid);
  EXPECT_TRUE(s.health.frozen);
  EXPECT_TRUE(s.flags & kFlagFrozen) << s.flags;
}

// The true delay (7 samples) outside the bank: the selection sits on the edge nearest to it.
TEST(OnlineIntegratorDelayHealth, OutOfBoundsWhenTheDelayIsAtAnEdgeOfTheBank) {
  const IntegratorDelaySnapshot below = RunBank(Options(0, 5), PoolSpec{});
  EXPECT_EQ(below.delay_samples, 5);
  EXPECT_TRUE(below.flags & kFlagOutOfBounds) << below.flags;
  const IntegratorDelaySnapshot above = RunBank(Options(9, 15), PoolSpec{});
  EXPECT_EQ(above.delay_samples, 9);
  EXPECT_TRUE(above.flags & kFlagOutOfBounds) << above.flags;
}

// The soak's estimate: a negative area.  And the NaN flag: the estimator's guards reject
// non-finite samples, so a NaN parameter is built here directly in a snapshot.
TEST(OnlineIntegratorDelayHealth, NegativeAreaIsOutOfBoundsAndNanParametersAreFlagged) {
  const OnlineIntegratorDelayOptions o = Options();
  IntegratorDelaySnapshot s = RunBank(o, PoolSpec{}, 7);
  ASSERT_EQ(IntegratorDelaySnapshotFlags(s, o), 0);
  s.b = 60.0 / -133093.0;
  s.area_m2 = -133093.0;
  EXPECT_EQ(IntegratorDelaySnapshotFlags(s, o), kFlagOutOfBounds);
  s.b = std::numeric_limits<double>::quiet_NaN();
  s.area_m2 = s.b;
  EXPECT_EQ(IntegratorDelaySnapshotFlags(s, o), kFlagNan | kFlagOutOfBounds);
  s.valid = false;
  EXPECT_EQ(IntegratorDelaySnapshotFlags(s, o), 0);
}

TEST(OnlineIntegratorDelayHealth, BoundsProblemsNameTheValue) {
  const OnlineIntegratorDelayOptions o = Options(2, 15);
  EXPECT_EQ(IntegratorDelayBoundsProblem(6000.0, 7, o), "");
  EXPECT_EQ(IntegratorDelayBoundsProblem(-133093.0, 7, o), "area_m2 -133093 is not > 0 and finite");
  EXPECT_EQ(IntegratorDelayBoundsProblem(6000.0, 16, o),
            "delay 16 samples is outside the bank [2, 15]");
  EXPECT_EQ(IntegratorDelayBoundsProblem(6000.0, 15, o),
            "delay 15 samples is at the edge of the bank [2, 15]: the true delay may lie outside "
            "it");
  EXPECT_NE(IntegratorDelayBoundsProblem(6000.0, 2, o), "");
  EXPECT_EQ(IntegratorDelayBoundsProblem(6000.0, 0, Options(0, 15)), "");  // no delay below 0
  EXPECT_NE(IntegratorDelayBoundsProblem(std::nan(""), 7, o), "");
}

// At the least-squares kinds' P0 of 1e10 the relative threshold (100 / p0 = 1e-8) alone would
// pass almost anything; the floor keeps the threshold at least 1e-4.
TEST(OnlineIntegratorDelayHealth, TheLowExcitationFloorHoldsAtALargeP0) {
  PoolSpec spec;
  spec.q_in_amplitude_m3s = 0.0;
  spec.q_out_amplitude_m3s = 0.0;
  spec.offtake_m3s = 0.0;
  OnlineIntegratorDelayOptions o = Options();
  o.rls.initial_covariance = 1e10;
  o.health.information_min_per_p0 = 0.0;  // the floor alone
  const IntegratorDelaySnapshot floored = RunBank(o, spec, 7);
  ASSERT_TRUE(floored.valid);
  EXPECT_NEAR(floored.information_min, 1e-10, 1e-16);  // the prior's, along b
  EXPECT_TRUE(floored.flags & kFlagLowExcitation) << floored.flags;
  o.health.information_min_floor = 0.0;
  o.health.level_resolution_m = 0.0;  // no swing at all: that rule would flag it too
  EXPECT_FALSE(RunBank(o, spec, 7).flags & kFlagLowExcitation);
}

// The default pool's flow term swings the level by centimetres; flows 1e5 times smaller, measured
// without noise, give the right area from a swing no level sensor resolves (~1e-7 m). The
// information floors are off here, so only the level-resolution rule can flag it. Between the
// two, the swing is b rms(Q_nk) computed independently from the data: Q_nk's residual after the
// offset and drift, times the true b.
TEST(OnlineIntegratorDelayHealth, LowExcitationWhenTheFlowExplainsASwingBelowTheResolution) {
  OnlineIntegratorDelayOptions o = Options();
  o.rls.initial_covariance = 1e10;  // the data, not the prior, decides b
  o.health.information_min_per_p0 = 0.0;
  o.health.information_min_floor = 0.0;
  const IntegratorDelaySnapshot moving = RunBank(o, PoolSpec{}, 7);
  ASSERT_TRUE(moving.valid);
  EXPECT_GT(moving.flow_level_rms_m, 1e-3);
  EXPECT_FALSE(moving.flags & kFlagLowExcitation) << moving.flags;

  PoolSpec still;
  still.q_in_amplitude_m3s = 2e-6;
  still.q_out_amplitude_m3s = 1e-6;
  still.offtake_m3s = 0.0;
  still.noise_m = 0.0;
  const IntegratorDelaySnapshot s = RunBank(o, still, 7);
  ASSERT_TRUE(s.valid);
  EXPECT_NEAR(s.area_m2, 6000.0, 60.0);  // noise-free: right, but from a swing of ~1e-7 m
  EXPECT_LT(s.flow_level_rms_m, 1e-5);
  EXPECT_GT(s.flow_level_rms_m, 1e-9);
  EXPECT_TRUE(s.flags & kFlagLowExcitation) << s.flags;
  // The swing against the data: Q_7(k) from the flows, detrended by least squares on [1, k].
  const testdata::PoolData d = MakePool(still);
  const int k0 = o.max_delay_samples + 1;
  std::vector<double> q;
  double sum = 0.0;
  for (int k = k0; k < still.samples; ++k) {
    sum += d.q_in[static_cast<std::size_t>(k - 7)] - d.q_out[static_cast<std::size_t>(k - 1)];
    q.push_back(sum);
  }
  const auto n = static_cast<double>(q.size());
  double st = 0.0, sq = 0.0, stt = 0.0, stq = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    const auto t = static_cast<double>(i);
    st += t;
    sq += q[i];
    stt += t * t;
    stq += t * q[i];
  }
  const double slope = (n * stq - st * sq) / (n * stt - st * st);
  const double intercept = (sq - slope * st) / n;
  double ss = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    const double r = q[i] - intercept - slope * static_cast<double>(i);
    ss += r * r;
  }
  EXPECT_NEAR(s.flow_level_rms_m, still.b * std::sqrt(ss / n), 0.02 * s.flow_level_rms_m);
  o.health.level_resolution_m = 0.0;
  EXPECT_FALSE(RunBank(o, still, 7).flags & kFlagLowExcitation);
}

TEST(OnlineIntegratorDelayHealth, BadThresholdsThrow) {
  OnlineIntegratorDelayOptions o = Options();
  o.health.condition_max = 0.5;
  EXPECT_THROW(OnlineIntegratorDelayBank{o}, std::invalid_argument);
  o = Options();
  o.health.information_min_per_p0 = -1.0;
  EXPECT_THROW(OnlineIntegratorDelayBank{o}, std::invalid_argument);
  o = Options();
  o.health.information_min_floor = -1.0;
  EXPECT_THROW(OnlineIntegratorDelayBank{o}, std::invalid_argument);
  o = Options();
  o.health.level_resolution_m = std::numeric_limits<double>::infinity();
  EXPECT_THROW(OnlineIntegratorDelayBank{o}, std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
