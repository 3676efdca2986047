// The PLC wired to the plant, without a network: the register image after master writes, word
// order, offtake and inflow setpoints reaching the plant, real-time mode ignoring the step
// register, negative spikes.  ASCE canal 2 at its steady state (2.1 m in pool 2, 11 m3/s in).
#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include <string>

#include "core/registers/register_codec.h"
#include "sim/canal_config.h"
#include "sim/plc/plc_config.h"
#include "sim/plc/plc_simulation.h"
#include "sim/plc/register_map.h"

namespace canalid::sim::plc {
namespace {

const std::string kCanal = std::string(CANALID_SOURCE_DIR) + "/config/sim/asce-canal2.toml";
const std::string kPlc = std::string(CANALID_SOURCE_DIR) + "/config/sim/plc/asce2.toml";

// Writes registers as a master would and lets the PLC act on them.
void Write(PlcSimulation* sim, int address, std::initializer_list<std::uint16_t> values) {
  std::size_t i = 0;
  for (std::uint16_t v : values)
    sim->holding_registers().at(static_cast<std::size_t>(address) + i++) = v;
  sim->OnHoldingWrite(address, static_cast<int>(values.size()));
}

TEST(PlcSimulation, CdabFloatsInTheImage) {
  const Canal canal = LoadCanal(kCanal);
  PlcConfig config = DefaultPlcConfig(canal);
  config.word_order = core::WordOrder::kLowWordFirst;
  PlcSimulation sim(canal, config, true);
  const std::uint16_t* level = &sim.input_registers()[static_cast<std::size_t>(
      InputFloatAddress(config, 1, kLevelDownstream))];
  EXPECT_NEAR(modbus_get_float_cdab(level), 2.1, 1e-3);  // libmodbus decodes independently
  EXPECT_GT(std::abs(modbus_get_float_abcd(level) - 2.1), 0.1);
  // A float setpoint written low word first reaches the PLC and its 16-bit mirror.
  // 1.25f is 0x3FA00000.  (Not libmodbus 3.1.6's modbus_set_float_*: they swap the bytes of
  // each word wrongly on little-endian hosts; its getters are right.)
  Write(&sim, HoldingFloatAddress(config, 1, kStructureSetpoint), {0x0000, 0x3FA0});
  EXPECT_DOUBLE_EQ(sim.logic().structure_setpoint(1), 1.25);
  EXPECT_EQ(sim.holding_registers()[static_cast<std::size_t>(
                HoldingScaledAddress(config, 1, kStructureSetpoint))],
            1250);
}

TEST(PlcSimulation, OfftakeAndInflowSetpointsReachThePlant) {
  const Canal canal = LoadCanal(kCanal);
  const PlcConfig config = LoadPlcConfig(kPlc, canal);
  PlcSimulation sim(canal, config, true);
  Write(&sim, HoldingScaledAddress(config, 1, kOfftakeSetpoint), {2000});  // 2 m3/s
  Write(&sim, kHrUpstreamScaled, {12000});                                 // 12 m3/s
  Write(&sim, kHrStep, {1});
  EXPECT_EQ(sim.steps(), 1);
  // A fixed offtake takes its setting at once; the inflow ramps at 0.01 m3/s per s.
  EXPECT_NEAR(sim.plant().OfftakeFlow(1), 2.0, 1e-9);
  EXPECT_NEAR(sim.plant().upstream(), 11.1, 1e-9);
  EXPECT_EQ(
      sim.input_registers()[static_cast<std::size_t>(InputScaledAddress(config, 1, kOfftakeFlow))],
      2000);
  EXPECT_EQ(sim.input_registers()[static_cast<std::size_t>(InputScaledAddress(config, 0, kInflow))],
            11100);
  EXPECT_EQ(sim.holding_registers()[kHrStep], 0);
}

TEST(PlcSimulation, RealTimeModeIgnoresTheStepRegister) {
  const Canal canal = LoadCanal(kCanal);
  PlcSimulation sim(canal, DefaultPlcConfig(canal), false);
  Write(&sim, kHrStep, {5});
  EXPECT_EQ(sim.steps(), 0);
  EXPECT_EQ(sim.holding_registers()[kHrStep], 0);
  EXPECT_EQ(sim.input_registers()[kIrStatus] & kStatusLockstep, 0);
  sim.Step();  // the transport's clock steps it
  EXPECT_EQ(sim.input_registers()[kIrStepCount], 1);
}

TEST(PlcSimulation, NegativeSpikesAndTheFaultWord) {
  const Canal canal = LoadCanal(kCanal);
  const PlcConfig config = DefaultPlcConfig(canal);
  PlcSimulation sim(canal, config, true);
  const auto level = static_cast<std::size_t>(InputScaledAddress(config, 1, kLevelUpstream));
  const std::uint16_t before = sim.input_registers()[level];
  // Every 3rd step, -300 mm.
  Write(&sim, kHrFaultSpikeMask, {1u << 1, static_cast<std::uint16_t>(-300), 3});
  EXPECT_EQ(sim.input_registers()[kIrFaults], kFaultSpike);
  EXPECT_TRUE(sim.input_registers()[kIrStatus] & kStatusFaultActive);
  for (int k = 1; k <= 6; ++k) {
    Write(&sim, kHrStep, {1});
    const int expected = before - (k % 3 == 0 ? 300 : 0);
    // At rest the upstream level holds within 1 mm.
    EXPECT_NEAR(sim.input_registers()[level], expected, 1) << k;
  }
  Write(&sim, kHrFaultDelayMs, {250, 4, 2});
  EXPECT_EQ(sim.input_registers()[kIrFaults],
            kFaultSpike | kFaultDelay | kFaultException | kFaultDrop);
  EXPECT_EQ(sim.response_delay_ms(), 250);
  EXPECT_EQ(sim.read_exception_code(), 4);
  EXPECT_TRUE(sim.TakeDrop());
  EXPECT_TRUE(sim.TakeDrop());
  EXPECT_FALSE(sim.TakeDrop());
}

}  // namespace
}  // namespace canalid::sim::plc
