// Speed of the Saint-Venant plant on all of ASCE canal 2 (8 pools, 28 km, dx = 100 m, 288
// nodes) at dt = 10 s (and 60 s). x_real_time = simulated seconds per wall-clock second.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <string>

#include "sim/canal_config.h"
#include "sim/saint_venant.h"

namespace {

void BM_Canal2OneHour(benchmark::State& state) {
  const canalid::sim::Canal canal = canalid::sim::LoadCanal(std::string(CANALID_BENCH_SOURCE_DIR) +
                                                            "/config/sim/asce-canal2.toml");
  canalid::sim::SaintVenantCanal plant(canal);
  const double dt = static_cast<double>(state.range(0));
  const int steps = static_cast<int>(3600.0 / dt);
  bool high = false;
  long iterations = 0, steps_taken = 0;
  for (auto _ : state) {
    // Alternate the inflow every simulated hour so that Newton has real work to do.
    high = !high;
    plant.SetUpstream(high ? 12.0 : 11.0);
    for (int k = 0; k < steps; ++k) {
      plant.Step(dt);
      iterations += plant.last_iterations();
    }
    steps_taken += steps;
    benchmark::DoNotOptimize(plant.DownstreamDepth(7));
  }
  state.counters["x_real_time"] = benchmark::Counter(
      3600.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["newton_per_step"] =
      static_cast<double>(iterations) / static_cast<double>(std::max(steps_taken, 1L));
  state.counters["nodes"] = [&] {
    int n = 0;
    for (int p = 0; p < plant.num_pools(); ++p) n += plant.num_nodes(p);
    return n;
  }();
}
BENCHMARK(BM_Canal2OneHour)->Arg(10)->Arg(60)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
