// ID model timings.  Run:  build/bench/id_bench --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true
// IdDelayScan/day: FitIntegratorDelay on one day of 1 s data (86 400 samples) with candidate delays
//   nk = 0..120: for each candidate the regression [Q, q_in(k-nk), 1, k] is solved by QR.
// IdentifyIntegratorDelay/day: the whole `canalid identify --model id` core (Hampel on the level,
// the scan,
//   closed-loop detection, IV and correlation cross-checks).
#include <benchmark/benchmark.h>

#include <random>

#include "core/integrator_delay/identify_integrator_delay.h"
#include "core/integrator_delay/integrator_delay_model.h"

namespace canalid::core {
namespace {

struct PoolRecord {
  Eigen::VectorXd q_in, q_out, level;
};

// The discrete ID model of ASCE canal 2 pool 2 (A = 34113 m2) at 1 s with a 682 s delay, a
// random binary inflow held 341 s, and 3 mm level noise.
PoolRecord MakeDay() {
  const Eigen::Index n = 86400;
  const int nk = 682;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.003);
  PoolRecord r{Eigen::VectorXd(n), Eigen::VectorXd::Constant(n, 10.0), Eigen::VectorXd(n)};
  double value = 10.0, y = 2.1;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (k % 341 == 0) value = 10.0 + ((rng() & 1U) ? 0.8 : -0.8);
    r.q_in(k) = value;
    if (k > 0) y += 1.0 / 34113.0 * ((k >= nk ? r.q_in(k - nk) : 10.0) - 10.0);
    r.level(k) = y + noise(rng);
  }
  return r;
}

void BM_IdDelayScanDay(benchmark::State& state) {
  const PoolRecord r = MakeDay();
  IntegratorDelayFitOptions options;
  options.min_nk = 600;  // 121 candidates around the truth, as a 0..120 scan at 6 s would be
  options.max_nk = 720;
  for (auto _ : state) {
    IntegratorDelayFit fit = FitIntegratorDelay(r.q_in, r.q_out, r.level, 1.0, options);
    benchmark::DoNotOptimize(fit.model.b);
  }
  state.SetItemsProcessed(state.iterations() * 121);
  state.SetLabel("121 candidates x 86400 samples");
}
BENCHMARK(BM_IdDelayScanDay)->Unit(benchmark::kMillisecond);

void BM_IdentifyIntegratorDelayDay(benchmark::State& state) {
  const PoolRecord r = MakeDay();
  IntegratorDelayIdentificationOptions options;
  options.fit.min_nk = 600;
  options.fit.max_nk = 720;
  for (auto _ : state) {
    IntegratorDelayIdentification result =
        IdentifyIntegratorDelay(r.q_in, r.q_out, r.level, 1.0, options);
    benchmark::DoNotOptimize(result.fit.model.b);
  }
}
BENCHMARK(BM_IdentifyIntegratorDelayDay)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace canalid::core
