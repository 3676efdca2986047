// Proves that the online paths never allocate, and that the batch delay scans allocate nothing per
// candidate delay: this executable replaces malloc/calloc/realloc
// (which Eigen and operator new use) with counting versions that forward to glibc.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdlib>
#include <new>
#include <utility>

#include "core/fractional/commensurate_state_space.h"
#include "core/online/online_arx.h"
#include "core/online/online_fractional.h"
#include "core/online/online_integrator_delay.h"
#include "core/online/online_model.h"
#include "core/online/rls.h"
#include "core/reach/reach_sample_processor.h"
#include "tests/core/commensurate_test_models.h"
#include "tests/core/online_test_data.h"

// glibc's own allocator entry points, which the counting versions forward to: their names are
// glibc's (reserved, not ours to style).
// NOLINTBEGIN(bugprone-reserved-identifier, readability-identifier-naming)
extern "C" void* __libc_malloc(std::size_t size);
extern "C" void* __libc_calloc(std::size_t count, std::size_t size);
extern "C" void* __libc_realloc(void* ptr, std::size_t size);
extern "C" void* __libc_memalign(std::size_t alignment, std::size_t size);
// NOLINTEND(bugprone-reserved-identifier, readability-identifier-naming)

namespace {
long g_allocations = 0;
}

extern "C" void* malloc(std::size_t size) {
  ++g_allocations;
  return __libc_malloc(size);
}
extern "C" void* calloc(std::size_t count, std::size_t size) {
  ++g_allocations;
  return __libc_calloc(count, size);
}
extern "C" void* realloc(void* ptr, std::size_t size) {
  ++g_allocations;
  return __libc_realloc(ptr, size);
}
extern "C" int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  ++g_allocations;
  *out = __libc_memalign(alignment, size);
  return *out ? 0 : 12;
}
// The replacements below pair malloc with free on purpose; GCC cannot see that after inlining.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  if (void* p = malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { free(p); }
void operator delete[](void* p) noexcept { free(p); }
void operator delete(void* p, std::size_t) noexcept { free(p); }
void operator delete[](void* p, std::size_t) noexcept { free(p); }

namespace canalid::core {
namespace {

TEST(OnlineAllocation, CounterSeesEigenAndNewAllocations) {
  const long before = g_allocations;
  {
    Eigen::VectorXd v(100);
    v.setZero();
    auto* p = new int(3);
    delete p;
  }
  EXPECT_GE(g_allocations - before, 2);
}

template <int N>
long AllocationsPerRun(RlsMethod method, int n) {
  RlsOptions options;
  options.method = method;
  options.forgetting = 0.98;
  options.trace_max = method == RlsMethod::kConstantTrace ? 10.0 : 1e3;
  options.eigen_min = method == RlsMethod::kNlms || method == RlsMethod::kUdDirectional ||
                              method == RlsMethod::kUdExponential
                          ? 0.0
                          : 1e-9;
  options.huber = 3.0;
  options.dead_zone = 0.1;
  options.cusum_threshold = 5.0;
  options.lower = Eigen::VectorXd::Constant(n, -10.0);
  options.upper = Eigen::VectorXd::Constant(n, 10.0);
  Rls<N> rls(options, n);
  typename Rls<N>::Vector phi(n);
  typename Rls<N>::Vector sd(n);
  testdata::TestRandom rnd(5);
  const long before = g_allocations;
  for (int k = 0; k < 500; ++k) {
    for (int i = 0; i < n; ++i) phi(i) = rnd.Normal();
    const double y = phi.sum() + 0.1 * rnd.Normal() + (k == 300 ? 1e6 : 0.0);
    rls.Update(phi, k == 200 ? std::numeric_limits<double>::quiet_NaN() : y);
    rls.StandardDeviations(sd);
  }
  return g_allocations - before;
}

class AllocationByMethod : public ::testing::TestWithParam<RlsMethod> {};

TEST_P(AllocationByMethod, RlsUpdateNeverAllocates) {
  EXPECT_EQ(AllocationsPerRun<4>(GetParam(), 4), 0);
  EXPECT_EQ(AllocationsPerRun<Eigen::Dynamic>(GetParam(), 8), 0);
}

INSTANTIATE_TEST_SUITE_P(All, AllocationByMethod,
                         ::testing::Values(RlsMethod::kUdDirectional, RlsMethod::kUdExponential,
                                           RlsMethod::kExponential, RlsMethod::kDirectional,
                                           RlsMethod::kConstantTrace, RlsMethod::kStabilised,
                                           RlsMethod::kKalman, RlsMethod::kNlms));

// Runs `bank` over 600 samples of a synthetic pool (a bad outflow at sample 300, a bad
// level at `bad_level_sample` when >= 0), taking a snapshot after every update, and returns the
// allocations made meanwhile.
long IntegratorDelayBankAllocations(OnlineIntegratorDelayBank& bank, int bad_level_sample = -1) {
  testdata::PoolSpec spec;
  spec.samples = 600;
  const testdata::PoolData d = testdata::MakePool(spec);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const long before = g_allocations;
  double sum = 0.0;
  for (std::size_t k = 0; k < d.level.size(); ++k) {
    const bool bad_level = static_cast<int>(k) == bad_level_sample;
    bank.Update(d.q_in[k], k == 300 ? nan : d.q_out[k], bad_level ? nan : d.level[k]);
    sum += bank.Snapshot().b;
  }
  const long allocations = g_allocations - before;
  EXPECT_TRUE(std::isfinite(sum));
  return allocations;
}

OnlineIntegratorDelayOptions IntegratorDelayBankOptions() {
  OnlineIntegratorDelayOptions o;
  o.sample_time_s = 60.0;
  o.max_delay_samples = 20;
  o.rls.forgetting = 0.99;  // re-centring every 100 samples is exercised too
  return o;
}

TEST(OnlineAllocation, IdBankUpdateAndSnapshotNeverAllocate) {
  const OnlineIntegratorDelayOptions o = IntegratorDelayBankOptions();
  OnlineIntegratorDelayBank bank(o);
  EXPECT_EQ(IntegratorDelayBankAllocations(bank), 0);
}

// The closed-loop variant: auto runs both banks through the decision, IV re-centring included.
TEST(OnlineAllocation, ClosedLoopIdBankUpdateAndSnapshotNeverAllocate) {
  OnlineIntegratorDelayOptions o = IntegratorDelayBankOptions();
  o.wave_front_term = true;
  o.closed_loop = ClosedLoopMode::kAuto;
  o.closed_loop_window_samples = 250;
  o.outflow_direct_gain_s_per_m2 = 0.02;
  OnlineIntegratorDelayBank bank(o);
  EXPECT_EQ(IntegratorDelayBankAllocations(bank), 0);
  EXPECT_TRUE(bank.health().closed_loop_decided);
}

// The three-step variant: step (2), the simulation, step (3) with re-centring, a bad flow and a
// bad level, and the snapshots (covariance of step (3)) on every sample.
TEST(OnlineAllocation, ThreeStepIdBankUpdateAndSnapshotNeverAllocate) {
  OnlineIntegratorDelayOptions o = IntegratorDelayBankOptions();
  o.wave_front_term = true;
  o.closed_loop = ClosedLoopMode::kThreeStep;
  o.three_step.warmup_samples = 50;
  OnlineIntegratorDelayBank bank(o);
  EXPECT_EQ(IntegratorDelayBankAllocations(bank, 400), 0);
  EXPECT_TRUE(bank.Snapshot().valid);
}

// Allocations during `samples` updates and snapshots of a SISO bank on y = 0.9 y + 0.1 u + 0.01 e
// under a random binary u (TestRandom(seed)), with a NaN u at sample bad_input_sample (-1: none)
// and a NaN y at sample 100.  `probe` reads a snapshot value, which must stay finite.
template <class Bank, class Probe>
long SisoBankAllocations(Bank& bank, std::uint64_t seed, int samples, int bad_input_sample,
                         Probe probe) {
  testdata::TestRandom rnd(seed);
  const long before = g_allocations;
  double sum = 0.0;
  double y = 0.0;
  for (int k = 0; k < samples; ++k) {
    const double u = rnd.Uniform() < 0.5 ? -1.0 : 1.0;
    y = 0.9 * y + 0.1 * u + 0.01 * rnd.Normal();
    bank.Update(k == bad_input_sample ? std::numeric_limits<double>::quiet_NaN() : u,
                k == 100 ? std::numeric_limits<double>::quiet_NaN() : y);
    sum += probe(bank.Snapshot());
  }
  const long allocations = g_allocations - before;
  EXPECT_TRUE(std::isfinite(sum));
  return allocations;
}

TEST(OnlineAllocation, ArxBankUpdateAndSnapshotNeverAllocate) {
  OnlineArxOptions o;
  o.na = 3;
  o.nb = 3;
  o.min_delay_samples = 1;
  o.max_delay_samples = 10;
  o.rls.forgetting = 0.99;
  OnlineArxBank bank(o);
  EXPECT_EQ(SisoBankAllocations(bank, 3, 500, -1, [](const ArxSnapshot& s) { return s.a_std(0); }),
            0);
}

TEST(OnlineAllocation, FractionalBankUpdateAndSnapshotNeverAllocate) {
  OnlineFractionalOptions o;
  o.sample_time_s = 0.5;
  o.memory_samples = 100;
  o.delay_samples = 1;
  OnlineFractionalBank bank(o);
  EXPECT_EQ(
      SisoBankAllocations(bank, 4, 400, 50, [](const FractionalSnapshot& s) { return s.gain; }), 0);
}

// Every kind of the online registry, as the daemon runs it (Update, then FillSnapshot for the
// publication), with bad values of each input on the way.
TEST(OnlineAllocation, EveryOnlineModelKindUpdatesAndSnapshotsWithoutAllocating) {
  OnlineModelSettings settings;
  settings.sample_time_s = 1.0;
  settings.max_delay_s = 8.0;
  settings.forgetting = 0.99;
  settings.fractional_delay_s = 1.0;
  settings.lpv_delay_s = 1.0;
  for (const OnlineModelKind kind : kOnlineModelKinds) {
    auto model = MakeOnlineModel(OnlineModelOptionsFor(kind, settings));
    OnlineModelSnapshot snapshot;
    testdata::TestRandom rnd(9);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const long before = g_allocations;
    double y = 0.0, sum = 0.0;
    for (int k = 0; k < 500; ++k) {
      const double u = rnd.Uniform() < 0.5 ? -1.0 : 1.0;
      y = 0.9 * y + 0.1 * u + 0.01 * rnd.Normal();
      const OnlineSample s{1.0 + 0.1 * u, 1.0, k == 100 ? nan : y, k == 150 ? nan : u,
                           k == 200 ? nan : 0.5 + 0.1 * u};
      model->Update(s);
      model->FillSnapshot(snapshot);
      // Every parameter of a valid snapshot is finite (frac-ss's first is its fixed delay).
      for (int p = 0; snapshot.valid && p < snapshot.num_params; ++p) {
        sum += snapshot.values[static_cast<std::size_t>(p)];
      }
    }
    EXPECT_EQ(g_allocations - before, 0) << OnlineModelKindName(kind);
    EXPECT_TRUE(std::isfinite(sum)) << OnlineModelKindName(kind);
  }
}

// A reach running every kind at once: OnSample allocates nothing.
TEST(OnlineAllocation, AReachRunningEveryKindDoesNotAllocatePerSample) {
  OnlineModelSettings settings;
  settings.sample_time_s = 60.0;
  settings.max_delay_s = 20 * 60.0;
  settings.fractional_delay_s = 120.0;
  settings.lpv_delay_s = 120.0;
  settings.frac_ss_delay_s = 120.0;
  ReachSampleProcessorOptions options;
  options.sample_time_s = 60.0;
  options.online_id = OnlineModelOptionsFor(OnlineModelKind::kIntegratorDelay, settings).id;
  for (const OnlineModelKind kind : {OnlineModelKind::kArx, OnlineModelKind::kFractionalFoptd,
                                     OnlineModelKind::kLpvArx, OnlineModelKind::kFracSs}) {
    options.process_models.push_back(OnlineModelOptionsFor(kind, settings));
  }
  ReachSampleProcessor reach(options);
  ASSERT_EQ(reach.online_models().size(), 5U);
  testdata::PoolSpec spec;
  spec.samples = 600;
  const testdata::PoolData d = testdata::MakePool(spec);
  const long before = g_allocations;
  std::uint32_t updated = 0;
  for (std::size_t k = 0; k < d.level.size(); ++k) {
    ReachSample s;
    s.q_in_m3s = d.q_in[k];
    s.q_out_m3s = d.q_out[k];
    s.level_m = d.level[k];
    s.q_in_valid = s.q_out_valid = s.level_valid = true;
    s.input = d.q_in[k];
    s.scheduling = d.level[k];
    s.time_s = 60.0 * static_cast<double>(k);
    updated |= reach.OnSample(s).online_models_updated;
  }
  EXPECT_EQ(g_allocations - before, 0);
  EXPECT_EQ(updated, 0x1FU);  // every model moved
}

// The frac-ss delay scan fits and simulates every candidate delay in one set of buffers: a scan
// over 26 delays allocates exactly as often as one over a single delay.
TEST(BatchScanAllocation, CommensurateDelayScanAllocatesNothingPerCandidate) {
  const CommensurateModel plant = testdata::SeedOneHalf();  // nk = 17
  Eigen::VectorXd u(600);
  for (Eigen::Index k = 0; k < u.size(); ++k) u(k) = (k / 40) % 2 == 0 ? 0.0 : 1.0;
  const Eigen::VectorXd y = SimulateCommensurate(plant, u);
  CommensurateFitOptions options;
  options.refine = false;
  const auto allocations = [&](int max_delay) {
    const long before = g_allocations;
    const CommensurateFitResult fit = FitCommensurateScanDelay(u, y, 2, max_delay, 0.5, options);
    const long count = g_allocations - before;
    EXPECT_TRUE(fit.model.a.allFinite());
    return std::pair{count, fit.model.delay_samples};
  };
  const auto [one, one_delay] = allocations(0);
  const auto [many, found_delay] = allocations(25);
  EXPECT_EQ(one_delay, 0);
  EXPECT_EQ(found_delay, 17);  // the scan did look at the other candidates
  EXPECT_GT(one, 0);
  EXPECT_EQ(many, one);
}

}  // namespace
}  // namespace canalid::core
