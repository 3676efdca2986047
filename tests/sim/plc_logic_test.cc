// The PLC's local logic driven with explicit plant time: travel-rate limits, clamps, the
// heartbeat watchdog; and the PLC configuration file.  Truths are closed forms (distance =
// rate x time) and the numbers written in the test.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "sim/canal_config.h"
#include "sim/config_reader.h"
#include "sim/plc/plc_config.h"
#include "sim/plc/plc_logic.h"
#include "tests/support/run_program.h"

namespace canalid::sim::plc {
namespace {

PlcConfig TwoPools() {
  PlcConfig c;
  c.heartbeat_timeout_s = 300.0;
  c.upstream_min_m3s = 0.0;
  c.upstream_max_m3s = 15.0;
  c.upstream_rate_m3s_per_s = 0.01;
  c.pools = {{"1", 0, 0.05, 2.5, 0.005, 0.0, 3.0}, {"2", 1, 0.0, 1.9, 0.0, 0.0, 3.0}};
  return c;
}

PlcLogic Make(const PlcConfig& c) { return PlcLogic(c, {1.5, 0.8}, {1.0, 0.5}, 11.0, 0.0); }

TEST(PlcLogic, StartsAtTheNominalSettings) {
  PlcLogic plc = Make(TwoPools());
  EXPECT_DOUBLE_EQ(plc.structure_setting(0), 1.5);
  EXPECT_DOUBLE_EQ(plc.structure_setpoint(1), 0.8);
  EXPECT_DOUBLE_EQ(plc.offtake_setpoint(1), 0.5);
  EXPECT_DOUBLE_EQ(plc.upstream_flow_m3s(), 11.0);
  EXPECT_FALSE(plc.moving());
}

TEST(PlcLogic, GateTravelsAtItsRateLimit) {
  PlcConfig c = TwoPools();
  c.heartbeat_timeout_s = 0.0;  // this test runs past the watchdog's timeout
  PlcLogic plc = Make(c);
  plc.SetStructureSetpoint(0, 1.0);
  EXPECT_FALSE(plc.clamped());
  // 0.005 m/s for 10 s is 0.05 m per call; 0.5 m takes 100 s.
  for (int k = 1; k <= 9; ++k) {
    plc.Advance(10.0 * k);
    EXPECT_NEAR(plc.structure_setting(0), 1.5 - 0.05 * k, 1e-12) << k;
    EXPECT_TRUE(plc.moving());
  }
  plc.Advance(100.0);
  EXPECT_NEAR(plc.structure_setting(0), 1.0, 1e-12);
  plc.Advance(500.0);
  EXPECT_DOUBLE_EQ(plc.structure_setting(0), 1.0);  // no overshoot
  EXPECT_FALSE(plc.moving());
  // Upward travel is limited the same way; an uneven interval moves rate x interval.
  plc.SetStructureSetpoint(0, 2.0);
  plc.Advance(503.0);
  EXPECT_NEAR(plc.structure_setting(0), 1.015, 1e-12);
}

TEST(PlcLogic, NoRateLimitFollowsAtOnceAndTimeBackwardsDoesNotMove) {
  PlcLogic plc = Make(TwoPools());
  plc.SetStructureSetpoint(1, 1.2);
  plc.Advance(0.0);  // zero elapsed time, but pool 2 has no limit
  EXPECT_DOUBLE_EQ(plc.structure_setting(1), 1.2);
  plc.SetStructureSetpoint(0, 0.5);
  plc.Advance(100.0);
  const double at_100 = plc.structure_setting(0);
  plc.Advance(50.0);
  EXPECT_DOUBLE_EQ(plc.structure_setting(0), at_100);
}

TEST(PlcLogic, SetpointsAreClampedToThePlcLimits) {
  PlcLogic plc = Make(TwoPools());
  EXPECT_DOUBLE_EQ(plc.SetStructureSetpoint(0, 5.0), 2.5);
  EXPECT_TRUE(plc.clamped());
  EXPECT_DOUBLE_EQ(plc.SetStructureSetpoint(0, -1.0), 0.05);
  EXPECT_TRUE(plc.clamped());
  EXPECT_DOUBLE_EQ(plc.SetStructureSetpoint(0, 1.0), 1.0);
  EXPECT_FALSE(plc.clamped());
  EXPECT_DOUBLE_EQ(plc.SetOfftakeSetpoint(1, 7.0), 3.0);
  EXPECT_DOUBLE_EQ(plc.SetUpstreamSetpoint(20.0), 15.0);
  EXPECT_DOUBLE_EQ(plc.SetStructureSetpoint(1, std::nan("")), 0.0);  // NaN goes to the minimum
}

TEST(PlcLogic, UpstreamInflowRamps) {
  PlcLogic plc = Make(TwoPools());
  plc.SetUpstreamSetpoint(12.0);
  plc.Advance(10.0);  // 0.01 m3/s per s
  EXPECT_NEAR(plc.upstream_flow_m3s(), 11.1, 1e-12);
  plc.Advance(200.0);
  EXPECT_DOUBLE_EQ(plc.upstream_flow_m3s(), 12.0);
}

TEST(PlcLogic, HeartbeatTimeoutReturnsSetpointsToNominal) {
  PlcLogic plc = Make(TwoPools());
  plc.Heartbeat(1, 0.0);
  plc.SetStructureSetpoint(0, 1.0);
  plc.SetOfftakeSetpoint(0, 2.0);
  plc.SetUpstreamSetpoint(12.0);
  plc.Advance(299.0);
  EXPECT_FALSE(plc.heartbeat_lost());
  EXPECT_DOUBLE_EQ(plc.structure_setpoint(0), 1.0);
  plc.Heartbeat(1, 299.0);  // the same value is no heartbeat
  plc.Advance(300.0);
  EXPECT_TRUE(plc.heartbeat_lost());
  EXPECT_DOUBLE_EQ(plc.structure_setpoint(0), 1.5);
  EXPECT_DOUBLE_EQ(plc.offtake_setpoint(0), 1.0);
  EXPECT_DOUBLE_EQ(plc.upstream_setpoint_m3s(), 11.0);
  // While lost, writes are ignored; the gate travels back toward nominal at its rate.
  EXPECT_DOUBLE_EQ(plc.SetStructureSetpoint(0, 0.5), 1.5);
  const double before = plc.structure_setting(0);
  plc.Advance(310.0);
  EXPECT_NEAR(plc.structure_setting(0), before + 0.05, 1e-12);
  // A new heartbeat value restores remote control.
  plc.Heartbeat(2, 310.0);
  EXPECT_FALSE(plc.heartbeat_lost());
  EXPECT_DOUBLE_EQ(plc.SetStructureSetpoint(0, 0.5), 0.5);
  plc.Advance(609.0);
  EXPECT_FALSE(plc.heartbeat_lost());
  plc.Advance(610.0);
  EXPECT_TRUE(plc.heartbeat_lost());
}

TEST(PlcLogic, ZeroTimeoutDisablesTheWatchdog) {
  PlcConfig c = TwoPools();
  c.heartbeat_timeout_s = 0.0;
  PlcLogic plc = Make(c);
  plc.SetStructureSetpoint(0, 1.0);
  plc.Advance(1e6);
  EXPECT_FALSE(plc.heartbeat_lost());
  EXPECT_DOUBLE_EQ(plc.structure_setpoint(0), 1.0);
}

TEST(PlcLogic, RejectsNominalsOfTheWrongSize) {
  EXPECT_THROW(PlcLogic(TwoPools(), {1.0}, {1.0, 1.0}, 11.0, 0.0), std::invalid_argument);
}

const std::string kCanal = std::string(CANALID_SOURCE_DIR) + "/config/sim/asce-canal2.toml";

TEST(PlcConfig, LoadsTheAsce2Example) {
  const Canal canal = LoadCanal(kCanal);
  const PlcConfig c =
      LoadPlcConfig(std::string(CANALID_SOURCE_DIR) + "/config/sim/plc/asce2.toml", canal);
  ASSERT_EQ(c.pools.size(), 8u);
  EXPECT_EQ(c.pools[1].name, "2");
  EXPECT_EQ(c.pools[1].pool, 1);
  EXPECT_DOUBLE_EQ(c.pools[1].rate_per_s, 0.005);
  EXPECT_DOUBLE_EQ(c.pools[7].setpoint_max, 1.9);
  EXPECT_DOUBLE_EQ(c.heartbeat_timeout_s, 300.0);
  EXPECT_EQ(c.word_order, core::WordOrder::kHighWordFirst);
  EXPECT_EQ(c.input_float_base, 300);
}

// ParsePlcConfig (the text entry point of tests/fuzz) reads what LoadPlcConfig reads and names
// the given name.
TEST(PlcConfig, ParsesTextAsTheFileIsLoaded) {
  const Canal canal = LoadCanal(kCanal);
  const std::string path = std::string(CANALID_SOURCE_DIR) + "/config/sim/plc/asce2.toml";
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  const PlcConfig loaded = LoadPlcConfig(path, canal);
  const PlcConfig parsed = ParsePlcConfig(text.str(), "plc.toml", canal);
  ASSERT_EQ(parsed.pools.size(), loaded.pools.size());
  EXPECT_DOUBLE_EQ(parsed.pools[7].setpoint_max, loaded.pools[7].setpoint_max);
  EXPECT_DOUBLE_EQ(parsed.heartbeat_timeout_s, loaded.heartbeat_timeout_s);
  EXPECT_EQ(parsed.input_float_base, loaded.input_float_base);
  try {
    ParsePlcConfig("plant_step_s = 10.0\nbogus = 1\n", "plc.toml", canal);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_THAT(std::string(e.what()), ::testing::ContainsRegex("plc.toml:2:[0-9]+: unknown key"));
  }
}

TEST(PlcConfig, ReportsEveryProblemWithItsLocation) {
  const auto dir = testing::TestDirectory("plc_config_errors");
  const auto path = dir / "bad.toml";
  testing::WriteFile(path,
                     "plant_step_s = 10\n"
                     "bogus = 1\n"
                     "[registers]\n"
                     "float_word_order = \"big\"\n"
                     "[[pool]]\n"
                     "name = \"9\"\n"
                     "[[pool]]\n"
                     "name = \"2\"\n"
                     "rate_per_s = -1\n");
  try {
    LoadPlcConfig(path.string(), LoadCanal(kCanal));
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    const std::string all = e.what();
    // The column of an unknown key is its key or its value, depending on the reader version.
    EXPECT_THAT(all, ::testing::ContainsRegex("bad.toml:2:[0-9]+: unknown key 'bogus'"));
    EXPECT_NE(all.find(":4:20: 'registers.float_word_order'"), std::string::npos) << all;
    EXPECT_NE(all.find(":6:8: 'pool[0].name' = \"9\" is not a pool"), std::string::npos) << all;
    EXPECT_NE(all.find(":9:14: 'pool[1].rate_per_s' = -1 is outside"), std::string::npos) << all;
  }
}

TEST(PlcConfig, OverlappingBlocksAreRejected) {
  PlcConfig c = TwoPools();
  c.input_scaled_base = 100;
  c.input_float_base = 110;  // the 16-bit block of 2 pools is [100, 116)
  EXPECT_THROW(ValidatePlcConfig(c), std::invalid_argument);
  c.input_float_base = 116;
  EXPECT_NO_THROW(ValidatePlcConfig(c));
  c.holding_scaled_base = 5;  // inside the system block [0, 20)
  EXPECT_THROW(ValidatePlcConfig(c), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::sim::plc
