// Cost of the fractional-order simulators and of a full fractional FOPTD fit.
//   build/bench/fractional_bench
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "core/fractional/fractional_foptd.h"
#include "core/fractional/fractional_foptd_fit.h"
#include "core/fractional/fractional_simulator.h"

namespace canalid::core {
namespace {

const FractionalFoptdParams kNominal{0.372, 10.975, 0.8, 4.05};  // the flume paper's nominal plant
constexpr double kTs = 0.15;

// GL1 cost per internal step is one dot product over the memory (here L = 1000, 1 substep).
void BM_GrunwaldLetnikovStepMemory1000(benchmark::State& state) {
  GlFoptdSimulator sim(kNominal, kTs, 1, 1000);
  double u = 1.0;
  for (auto _ : state) {
    sim.Advance(u);
    benchmark::DoNotOptimize(sim.output());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_GrunwaldLetnikovStepMemory1000);

// Oustaloup: one dense n x n product per sample (n = 25 at 3 sections/decade for a 360 s
// record at Ts = 0.15 s, the simulator's default band).
void BM_OustaloupStep(benchmark::State& state) {
  OustaloupOptions band = DefaultOustaloupOptions(kNominal, kTs, 360.0);
  band.sections_per_decade = static_cast<double>(state.range(0));
  OustaloupFoptdSimulator sim(kNominal, kTs, band);
  for (auto _ : state) {
    sim.Advance(1.0);
    benchmark::DoNotOptimize(sim.output());
  }
  state.counters["states"] = sim.state_size();
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_OustaloupStep)->Arg(2)->Arg(3);

// Set-up (matrix exponentials) plus 2,400 samples.
void BM_OustaloupSimulate2400(benchmark::State& state) {
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(2400);
  for (auto _ : state) {
    benchmark::DoNotOptimize(SimulateFractionalFoptd(kNominal, u, kTs));
  }
}
BENCHMARK(BM_OustaloupSimulate2400)->Unit(benchmark::kMicrosecond);

// A full fit of a seed-2-like gate step: 2,400 samples, 0.15 mm noise.
void BM_FitFractionalFoptd2400(benchmark::State& state) {
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 0.15);
  Eigen::VectorXd u(2400), y(2400);
  for (int k = 0; k < 2400; ++k) {
    u(k) = k < 10 ? 20.0 : 40.0;
    y(k) = 60.0 + 20.0 * FractionalFoptdStepResponse(kNominal, (k - 10) * kTs) + noise(rng);
  }
  int simulations = 0;
  for (auto _ : state) {
    const FractionalFoptdFitResult r = FitFractionalFoptd(u, y, kTs);
    simulations = r.simulations;
    benchmark::DoNotOptimize(r.params.alpha);
  }
  state.counters["simulations"] = simulations;
}
BENCHMARK(BM_FitFractionalFoptd2400)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace canalid::core
