// Cost per sample of the transfer-function plants built from model JSON kinds (sim/): Output then
// Advance with a changing input, as `canalsim plant` and a test harness drive them.
#include <benchmark/benchmark.h>

#include <cmath>

#include "sim/commensurate_plant.h"
#include "sim/lpv_arx_plant.h"
#include "sim/soptd_plant.h"

namespace {

using canalid::sim::SampledPlant;

void Drive(benchmark::State& state, SampledPlant& plant, Eigen::VectorXd inputs) {
  long k = 0;
  for (auto _ : state) {
    inputs(0) = (k++ / 37) % 2 ? 1.0 : -1.0;
    benchmark::DoNotOptimize(plant.Output(inputs));
    plant.Advance(inputs);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_SoptdPlant(benchmark::State& state) {
  // K 0.8, T1 50 s, T2 12 s, tau 17.3 s at Ts = 2 s (a ring of 10 inputs).
  canalid::sim::SoptdPlant plant({0.8, {50.0, 12.0}, 17.3}, 2.0, 0.0, 0.0, 0.0);
  Drive(state, plant, Eigen::VectorXd::Zero(1));
}
BENCHMARK(BM_SoptdPlant);

void BM_CommensuratePlant(benchmark::State& state) {
  // q = 2 (four states), GL memory of state.range(0) samples.
  canalid::core::CommensurateModel model;
  model.q = 2;
  model.a = Eigen::Vector4d(1.99, 1.12, 0.56, 0.0176);
  model.c = Eigen::Vector3d(2.74, 2.93, 1.04);
  model.delay_samples = 20;
  canalid::sim::CommensuratePlant plant(model, static_cast<int>(state.range(0)), 0.15, 0.0, 0.0,
                                        0.0);
  Drive(state, plant, Eigen::VectorXd::Zero(1));
}
BENCHMARK(BM_CommensuratePlant)->Arg(100)->Arg(1000);

void BM_LpvArxPlant(benchmark::State& state) {
  // Quadratic laws of a1, b1 and nk in theta; theta held at 1.5 (nk = 3).
  canalid::core::LpvModel model;
  model.kind = "first_order_arx";
  model.degree = 2;
  model.coefficients.resize(3, 3);
  model.coefficients << 0.05, -0.2, -0.7, -0.02, 0.1, 0.05, 0.5, 0.0, 1.9;
  canalid::sim::LpvArxPlant plant(model, 10.0, 0.0, 0.0, 8);
  Drive(state, plant, Eigen::Vector2d(0.0, 1.5));
}
BENCHMARK(BM_LpvArxPlant);

}  // namespace
