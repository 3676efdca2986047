#include "sim/pool_plant.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "tests/support/canal2_pool2.h"

namespace canalid::sim {
namespace {

// IDZ of ASCE canal 2 pool 2 at 10 m3/s (reference CSV): tau 682 s, A 34113 m2, p21 0.0185,
// p22 0.0216. Closed-form step response to dq_in at t0 (dq_out = 0):
//   y(t) = y0 + [t >= t0 + tau] * dq (p21 + (t - t0 - tau) / A).
TEST(IdzPlant, StepResponseIsTheClosedFormAtEverySample) {
  IdzPlant plant(682.0, 34113.0, 0.0185, 0.0216, 2.1, 10.0);
  for (int k = 0; k < 360; ++k) plant.Step(10.0);
  plant.SetFlows(11.0, 10.0);
  for (int k = 1; k <= 2160; ++k) {
    plant.Step(10.0);
    const double t = k * 10.0;  // since the step; tau = 682 s falls between samples
    const double expected = t >= 682.0 ? 2.1 + 0.0185 + (t - 682.0) / 34113.0 : 2.1;
    // Exact integration of held inputs: only round-off remains.
    ASSERT_NEAR(plant.level_m(), expected, 1e-12) << "t = " << t;
  }
}

TEST(IdzPlant, OutflowActsWithoutDelayAndIdHasNoJump) {
  IdzPlant idz(682.0, 34113.0, 0.0185, 0.0216, 2.1, 10.0);
  idz.SetFlows(10.0, 10.5);
  idz.Step(100.0);
  EXPECT_NEAR(idz.level_m(), 2.1 - 0.0216 * 0.5 - 100.0 * 0.5 / 34113.0, 1e-12);
  IdzPlant id(300.0, 1000.0, 0.0, 0.0, 1.0, 2.0);
  id.SetFlows(3.0, 2.0);
  id.Step(299.0);
  EXPECT_DOUBLE_EQ(id.level_m(), 1.0);
  id.Step(11.0);
  EXPECT_NEAR(id.level_m(), 1.0 + 10.0 / 1000.0, 1e-12);
  EXPECT_THROW(IdzPlant(-1.0, 1.0, 0, 0, 0, 0), std::invalid_argument);
  EXPECT_THROW(IdzPlant(1.0, 0.0, 0, 0, 0, 0), std::invalid_argument);
}

// A pulse of inflow shorter than the delay: the level integrates exactly its volume.
TEST(IdzPlant, PulseShorterThanTheDelayIsIntegratedExactly) {
  IdzPlant plant(500.0, 2000.0, 0.0, 0.0, 0.0, 1.0);
  plant.SetFlows(3.0, 1.0);
  plant.Step(7.0);
  plant.SetFlows(1.0, 1.0);
  for (int k = 0; k < 100; ++k) plant.Step(13.0);
  EXPECT_NEAR(plant.level_m(), 2.0 * 7.0 / 2000.0, 1e-14);
}

// The flume paper's nominal lab model: K 0.372, T 10.975 s, tau 4.05 s; the step response is
// K (1 - exp(-(t - tau)/T)) after the delay.
TEST(FoptdPlant, StepResponseIsTheClosedForm) {
  FoptdPlant plant(0.372, 10.975, 4.05, 0.5, 0.0);
  plant.SetFlows(1.0, 0.0);
  for (int k = 1; k <= 400; ++k) {
    plant.Step(0.15);
    const double t = k * 0.15;
    const double expected = t > 4.05 ? 0.5 + 0.372 * (1.0 - std::exp(-(t - 4.05) / 10.975)) : 0.5;
    ASSERT_NEAR(plant.level_m(), expected, 1e-12) << "t = " << t;
  }
  EXPECT_THROW(FoptdPlant(1.0, 0.0, 1.0, 0.0, 0.0), std::invalid_argument);
}

// The Saint-Venant pool behind the same interface: at rest it stays at its target depth; after a
// step its late level slope gives the pool's surface area (canal 2 pool 2: 41133 m2 measured by
// scenario_test, SWMM 41616 m2).
TEST(SaintVenantPool, SameInterfaceAsTheFastPlants) {
  const Pool pool = canalid::testing::Canal2Pool2();
  std::unique_ptr<PoolPlant> plant = std::make_unique<SaintVenantPool>(pool, 10.0, 100.0, 0.6);
  plant->SetFlows(10.0, 10.0);
  for (int k = 0; k < 60; ++k) plant->Step(10.0);
  EXPECT_NEAR(plant->level_m(), 2.1, 1e-9);
  plant->SetFlows(11.0, 10.0);
  for (int k = 0; k < 1800; ++k) plant->Step(10.0);
  const double y1 = plant->level_m();
  for (int k = 0; k < 360; ++k) plant->Step(10.0);
  const double area = 3600.0 / (plant->level_m() - y1);
  EXPECT_NEAR(area, 41616.0, 0.1 * 41616.0);  // the brief's 10 % tolerance
  EXPECT_DOUBLE_EQ(plant->time_s(), 22200.0);
}

}  // namespace
}  // namespace canalid::sim
