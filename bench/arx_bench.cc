// ARX and delay-scan timings.  Run:  build/bench/arx_bench --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true
// ArxFit/100k: na=nb=2 nk=1 on 100 000 samples (compare with Octave's arx, timed by
//   scripts/octave/arx_reference.m).
// DelayScan/day: one day of 1 s data (86 400 samples), candidates nk = 0..120, na=nb=2, by
//   ScanArxDelay (fixed regressors factorised once, Frisch-Waugh projection) and, for comparison,
//   by 121 independent FitArx calls on the same window.
// ArxOverDelays12k: the daemon's batch arx (FitArxOverDelays), 12 000 samples, delays 1..1200,
//   against 1200 full FitArx calls.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>

#include "core/linear/arx.h"
#include "core/linear/arx_delay_scan.h"
#include "core/linear/delay_estimation.h"

namespace canalid::core {
namespace {

struct Record {
  Eigen::VectorXd y;
  Eigen::MatrixXd u;
};

// y(t) = 1.2 y(t-1) - 0.35 y(t-2) + 0.8 u(t-nk) + 0.3 u(t-nk-1) + 0.05 e(t), binary input.
Record MakeRecord(Eigen::Index n, int nk) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> normal(0.0, 1.0);
  Record r{Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Zero(n, 1)};
  for (Eigen::Index t = 0; t < n; ++t) r.u(t, 0) = normal(rng) > 0 ? 1.0 : -1.0;
  for (Eigen::Index t = nk + 1; t < n; ++t) {
    r.y(t) = 1.2 * r.y(t - 1) - 0.35 * r.y(t - 2) + 0.8 * r.u(t - nk, 0) +
             0.3 * r.u(t - nk - 1, 0) + 0.05 * normal(rng);
  }
  return r;
}

void BM_ArxFit100k(benchmark::State& state) {
  const Record r = MakeRecord(100000, 1);
  const ArxOrders orders{2, {2}, {1}};
  for (auto _ : state) {
    ArxModel m = FitArx(r.y, r.u, orders);
    benchmark::DoNotOptimize(m.parameters.data());
  }
}
BENCHMARK(BM_ArxFit100k)->Unit(benchmark::kMillisecond);

void BM_DelayScanDay(benchmark::State& state) {
  const Record r = MakeRecord(86400, 47);
  ArxDelayScanOptions options;
  options.orders =
      ArxOrders{static_cast<int>(state.range(0)), {static_cast<int>(state.range(0))}, {0}};
  options.min_nk = 0;
  options.max_nk = 120;
  for (auto _ : state) {
    ArxDelayScan scan = ScanArxDelay(r.y, r.u, options);
    if (scan.refined_nk != 47) state.SkipWithError("wrong delay");
    benchmark::DoNotOptimize(scan.loss.data());
  }
}
BENCHMARK(BM_DelayScanDay)->Arg(2)->Arg(4)->Unit(benchmark::kMillisecond);

void BM_DelayScanDayNaive(benchmark::State& state) {
  const Record r = MakeRecord(86400, 47);
  const Eigen::Index first = 2 + 120 - 1;  // max(na, nb + max_nk - 1)
  for (auto _ : state) {
    double best = 1e300;
    for (int nk = 0; nk <= 120; ++nk) {
      const ArxModel m = FitArx(r.y, r.u, ArxOrders{2, {2}, {nk}}, first);
      best = std::min(best, m.loss);
    }
    benchmark::DoNotOptimize(best);
  }
}
BENCHMARK(BM_DelayScanDayNaive)->Unit(benchmark::kMillisecond);

// The daemon's batch arx at the end of a long experiment: 12 000 samples, delays 1..1200,
// na = nb = 2 (FitArxOverDelays: the scan in blocks, then FitArx at its delay) against fitting
// every candidate in full (what it did before), range(0) = 1 / 0.
void BM_ArxOverDelays12k(benchmark::State& state) {
  const Record r = MakeRecord(12000, 700);
  const Eigen::VectorXd u = r.u.col(0);
  const bool scan = state.range(0) != 0;
  for (auto _ : state) {
    if (scan) {
      const ArxModel m = FitArxOverDelays(r.y, u, 2, 2, 1, 1200);
      if (m.orders.nk[0] != 700) state.SkipWithError("wrong delay");
      benchmark::DoNotOptimize(m.parameters.data());
    } else {
      double best = 1e300;
      for (int nk = 1; nk <= 1200; ++nk) {
        const ArxModel m = FitArx(r.y, u, ArxOrders{2, {2}, {nk}}, 2 + 1200 - 1);
        best = std::min(best, m.loss);
      }
      benchmark::DoNotOptimize(best);
    }
  }
  state.SetLabel(scan ? "scan in blocks" : "every candidate in full");
}
BENCHMARK(BM_ArxOverDelays12k)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace canalid::core
