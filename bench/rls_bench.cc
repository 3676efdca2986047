// Cost of one RLS update per method and size, and of one sample through the online banks.
// Run: build/bench/rls_bench --benchmark_min_time=0.2
#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/online/online_arx.h"
#include "core/online/online_fractional.h"
#include "core/online/online_integrator_delay.h"
#include "core/online/rls.h"
#include "core/online/rls_bank.h"
#include "core/online/rls_iv.h"

namespace canalid::core {
namespace {

constexpr std::size_t kPool = 1024;  // pre-generated samples, cycled

double Lcg(std::uint64_t& state) {  // deterministic uniform in [-1, 1)
  state = state * 6364136223846793005ULL + 1442695040888963407ULL;
  return static_cast<double>(state >> 11) * 0x1.0p-52 - 1.0;
}

struct SisoRecord {
  std::vector<double> u;
  std::vector<double> y;
};

// kPool samples of x(k) = pole x(k-1) + gain u(k) (+ noise Lcg when noise > 0) under a random
// binary u.
SisoRecord FirstOrderRecord(std::uint64_t seed, double pole, double gain, double noise) {
  SisoRecord r{std::vector<double>(kPool), std::vector<double>(kPool)};
  double x = 0.0;
  for (std::size_t k = 0; k < kPool; ++k) {
    r.u[k] = Lcg(seed) > 0 ? 1.0 : -1.0;
    x = pole * x + gain * r.u[k];
    if (noise > 0.0) x += noise * Lcg(seed);
    r.y[k] = x;
  }
  return r;
}

// One bank.Update(u, y) per iteration, cycling through the record.
template <class Bank>
void RunSisoBank(benchmark::State& state, Bank& bank, const SisoRecord& record) {
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(bank.Update(record.u[k], record.y[k]));
    k = (k + 1) & (kPool - 1);
  }
}

const char* Name(RlsMethod m) {
  switch (m) {
    case RlsMethod::kUdDirectional:
      return "ud_directional(default)";
    case RlsMethod::kUdExponential:
      return "ud_exponential";
    case RlsMethod::kExponential:
      return "exponential";
    case RlsMethod::kDirectional:
      return "directional";
    case RlsMethod::kConstantTrace:
      return "constant_trace";
    case RlsMethod::kStabilised:
      return "stabilised";
    case RlsMethod::kKalman:
      return "kalman";
    case RlsMethod::kNlms:
      return "nlms";
  }
  return "?";
}

template <int N>
void BM_RlsUpdate(benchmark::State& state) {
  const auto method = static_cast<RlsMethod>(state.range(0));
  RlsOptions options;
  options.method = method;
  options.forgetting = 0.99;
  options.process_noise = 1e-6;
  if (method == RlsMethod::kConstantTrace) options.trace_max = 10.0;
  Rls<N> rls(options);
  std::vector<Eigen::Matrix<double, N, 1>> phis(kPool);
  std::vector<double> ys(kPool);
  std::uint64_t seed = 1;
  for (std::size_t k = 0; k < kPool; ++k) {
    for (int i = 0; i < N; ++i) phis[k](i) = Lcg(seed);
    ys[k] = phis[k].sum() + 0.01 * Lcg(seed);
  }
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(rls.Update(phis[k], ys[k]));
    k = (k + 1) & (kPool - 1);
  }
  state.SetLabel(Name(method));
}

void Methods(benchmark::internal::Benchmark* b) {
  for (int m = 0; m <= static_cast<int>(RlsMethod::kNlms); ++m) b->Arg(m);
}

BENCHMARK_TEMPLATE(BM_RlsUpdate, 2)->Apply(Methods);
BENCHMARK_TEMPLATE(BM_RlsUpdate, 4)->Apply(Methods);
BENCHMARK_TEMPLATE(BM_RlsUpdate, 8)->Apply(Methods);
BENCHMARK_TEMPLATE(BM_RlsUpdate, 16)->Apply(Methods);

// One sample through `lanes` estimators of n = N parameters with the same output: an RlsBank
// (structure of arrays; range(1) = 1: the CPU's best ISA, AVX-512VL here; 2: the baseline, SSE2;
// 3: AVX2) or the same number of Rls<N> one after the other (0, the peer).  UD directional
// forgetting, lambda = range(2) / 1000 (0.99; 1, the daemon's default, where the bank skips three
// divisions).  per_update: time per estimator update.
template <int N>
void BM_LaneUpdates(benchmark::State& state) {
  const int lanes = static_cast<int>(state.range(0));
  const bool soa = state.range(1) != 0;
  RlsOptions options;
  options.forgetting = static_cast<double>(state.range(2)) / 1000.0;
  const RlsBankIsa isa = state.range(1) == 2   ? RlsBankIsa::kBaseline
                         : state.range(1) == 3 ? RlsBankIsa::kAvx2
                                               : RlsBankIsa::kBest;
  if (isa == RlsBankIsa::kAvx2 && __builtin_cpu_supports("avx2") == 0) {
    state.SkipWithError("this CPU has no AVX2");
    return;
  }
  RlsBank<N> bank(options, lanes, isa);
  std::vector<Rls<N>> scalar(static_cast<std::size_t>(lanes), Rls<N>(options));
  std::vector<double> values(kPool * N);
  std::vector<double> ys(kPool);
  std::uint64_t seed = 1;
  for (double& v : values) v = Lcg(seed);
  for (double& y : ys) y = Lcg(seed);
  std::size_t k = 0;
  for (auto _ : state) {
    for (int l = 0; l < lanes; ++l) {
      // Each lane's regressor: the pool's samples at another offset (a delay bank's candidates).
      const std::size_t at = ((k + static_cast<std::size_t>(l)) & (kPool - 1)) * N;
      const Eigen::Map<const Eigen::Matrix<double, N, 1>> phi(&values[at]);
      if (soa) {
        bank.regressors().col(l) = phi;
      } else {
        benchmark::DoNotOptimize(scalar[static_cast<std::size_t>(l)].Update(phi, ys[k]));
      }
    }
    if (soa) bank.Update(ys[k]);
    benchmark::ClobberMemory();
    k = (k + 1) & (kPool - 1);
  }
  state.counters["per_update"] = benchmark::Counter(
      lanes, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  if (!soa) {
    state.SetLabel("Rls one by one");
  } else {
    state.SetLabel(bank.isa() == RlsBankIsa::kAvx512 ? "RlsBank AVX-512VL"
                   : bank.isa() == RlsBankIsa::kAvx2 ? "RlsBank AVX2"
                                                     : "RlsBank SSE2");
  }
}
BENCHMARK_TEMPLATE(BM_LaneUpdates, 3)->ArgsProduct({{24}, {0, 1, 2, 3}, {990, 1000}});
BENCHMARK_TEMPLATE(BM_LaneUpdates, 4)->ArgsProduct({{24, 64}, {0, 1, 2, 3}, {990, 1000}});
BENCHMARK_TEMPLATE(BM_LaneUpdates, 8)->ArgsProduct({{24}, {0, 1, 2, 3}, {990, 1000}});

// One IvRls<N> update (closed-loop variant; P not symmetric, plus the instruments' moment R).
template <int N>
void BM_IvRlsUpdate(benchmark::State& state) {
  RlsOptions options;
  options.forgetting = 0.99;
  IvRls<N> rls(options);
  std::vector<Eigen::Matrix<double, N, 1>> phis(kPool);
  std::vector<Eigen::Matrix<double, N, 1>> zs(kPool);
  std::vector<double> ys(kPool);
  std::uint64_t seed = 1;
  for (std::size_t k = 0; k < kPool; ++k) {
    for (int i = 0; i < N; ++i) zs[k](i) = Lcg(seed);
    phis[k] = zs[k];
    phis[k](0) += 0.3 * Lcg(seed);
    ys[k] = phis[k].sum() + 0.01 * Lcg(seed);
  }
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(rls.Update(phis[k], zs[k], ys[k]));
    k = (k + 1) & (kPool - 1);
  }
}
BENCHMARK_TEMPLATE(BM_IvRlsUpdate, 3);
BENCHMARK_TEMPLATE(BM_IvRlsUpdate, 4);

// One sample through a bank of 64 ID candidates (nk = 0..63), lambda 0.99 with re-centring.
// Arg 0: the daemon's default (3 parameters, least squares); 1: with the wave-front term, as
// `canalid identify --online --closed-loop off`; 2: closed loop, IvRls<4> (`--closed-loop iv`);
// 3: auto during its decision window (both banks); 4: the three-step method (`--closed-loop
// three-step`: the IvRls<4> bank for the delay plus one OnlineThreeStep per candidate, Rls<8> for
// F, its simulation and Rls<7> for the level).
void BM_IdBank64(benchmark::State& state) {
  OnlineIntegratorDelayOptions options;
  options.sample_time_s = 60.0;
  options.max_delay_samples = 63;
  options.rls.forgetting = 0.99;
  const auto variant = state.range(0);
  options.wave_front_term = variant >= 1;
  options.closed_loop = variant == 2   ? ClosedLoopMode::kOn
                        : variant == 3 ? ClosedLoopMode::kAuto
                        : variant == 4 ? ClosedLoopMode::kThreeStep
                                       : ClosedLoopMode::kOff;
  options.closed_loop_window_samples = 1000000000;
  OnlineIntegratorDelayBank bank(options);
  std::uint64_t seed = 3;
  std::vector<double> q_in(kPool);
  std::vector<double> q_out(kPool);
  std::vector<double> level(kPool);
  double y = 2.0;
  for (std::size_t k = 0; k < kPool; ++k) {
    q_in[k] = 2.0 + 0.2 * (Lcg(seed) > 0 ? 1 : -1);
    q_out[k] = 2.0 + 0.1 * Lcg(seed);
    y += 0.01 * (q_in[k] - q_out[k]);
    level[k] = y;
  }
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(bank.Update(q_in[k], q_out[k], level[k]));
    k = (k + 1) & (kPool - 1);
  }
  static const char* const kLabels[] = {"ls-3", "ls-4(wave front)", "iv-4(closed loop)",
                                        "auto window(ls-4 + iv-4)",
                                        "three-step(iv-4 + rls-8 + rls-7)"};
  state.SetLabel(kLabels[variant]);
}
BENCHMARK(BM_IdBank64)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->Arg(4);

// One sample through the fractional bank: 8 alphas (0.5..1.4) x 25 characteristic times, GL
// memory L = 200.
void BM_FractionalBank8(benchmark::State& state) {
  OnlineFractionalOptions options;
  options.sample_time_s = 0.5;
  options.memory_samples = 200;
  options.delay_samples = 2;
  options.rls.forgetting = 0.999;
  OnlineFractionalBank bank(options);
  RunSisoBank(state, bank, FirstOrderRecord(5, 0.95, 0.05, 0.0));
}
BENCHMARK(BM_FractionalBank8);

// One sample through an ARX(2, 2) bank over 16 delays (ArxCandidates: RlsBank<4> lanes).
void BM_ArxBank16(benchmark::State& state) {
  OnlineArxOptions options;
  options.min_delay_samples = 1;
  options.max_delay_samples = 16;
  options.rls.forgetting = 0.99;
  OnlineArxBank bank(options);
  RunSisoBank(state, bank, FirstOrderRecord(7, 0.9, 0.1, 0.01));
}
BENCHMARK(BM_ArxBank16);

}  // namespace
}  // namespace canalid::core
