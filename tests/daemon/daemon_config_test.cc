#include "daemon/config/daemon_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "daemon/config/plan_from_config.h"

namespace canalid::config {
namespace {

using ::testing::ElementsAre;
using ::testing::IsEmpty;

// A valid configuration: one TCP PLC, a reach on pool 2 of ASCE canal 2, a designed experiment.
DaemonConfig ValidConfig() {
  DaemonConfig c;
  c.daemon.time_scale = 50.0;
  PlcConfig& plc = c.plcs.emplace_back();
  plc.name = "plc1";
  plc.poll_period_s = 0.2;
  plc.response_timeout_s = 0.1;
  auto channel = [&](const char* name, ChannelRole role, RegisterTable table, int address) {
    ChannelConfig& ch = c.channels.emplace_back();
    ch.name = name;
    ch.plc = "plc1";
    ch.role = role;
    ch.table = table;
    ch.address = address;
    ch.type = RegisterType::kF32;
    return &ch;
  };
  channel("inflow", ChannelRole::kFlow, RegisterTable::kInput, 316);
  channel("outflow", ChannelRole::kFlow, RegisterTable::kInput, 318);
  channel("level", ChannelRole::kLevel, RegisterTable::kInput, 320);
  ChannelConfig* gate = channel("gate", ChannelRole::kGate, RegisterTable::kHolding, 300);
  gate->writable = true;
  gate->setpoint_min = 0.05;
  gate->setpoint_max = 2.0;
  gate->max_rate_per_s = 0.005;
  ReachConfig& reach = c.reaches.emplace_back();
  reach.name = "pool2";
  reach.inflow = "inflow";
  reach.outflow = "outflow";
  reach.level = "level";
  reach.actuator = "gate";
  reach.nominal_inflow_m3s = 10.0;
  reach.expected_delay_s = 682.0;
  reach.level_min_m = 1.9;
  reach.level_max_m = 2.3;
  reach.max_delay_s = 1400.0;
  ExperimentConfig& e = c.experiments.emplace_back();
  e.name = "prbs";
  e.reach = "pool2";
  e.settle_s = 600.0;
  return c;
}

std::vector<std::string> Problems(const DaemonConfig& c) {
  std::vector<std::string> out;
  for (const ConfigProblem& p : Validate(c)) out.push_back(p.path + ": " + p.message);
  return out;
}

TEST(DaemonConfigTest, ValidConfigHasNoProblem) { EXPECT_THAT(Problems(ValidConfig()), IsEmpty()); }

TEST(DaemonConfigTest, EnumNamesRoundTrip) {
  for (RlsMethod m : AllValues<RlsMethod>()) EXPECT_EQ(EnumFromName<RlsMethod>(EnumName(m)), m);
  EXPECT_EQ(AllowedNames<LogLevel>(), "error, warn, info, debug");
  EXPECT_EQ(AllowedNames<RegisterType>(), "u16, i16, u32, i32, f32");
  EXPECT_FALSE(EnumFromName<ChannelRole>("valve").has_value());
}

TEST(DaemonConfigTest, DanglingReferencesAndDuplicates) {
  DaemonConfig c = ValidConfig();
  c.channels[1].plc = "plc9";
  c.channels[2].name = "inflow";  // duplicate, and the reach's level no longer exists
  c.experiments[0].reach = "pool9";
  EXPECT_THAT(
      Problems(c),
      ElementsAre("channel[1].plc: unknown plc \"plc9\" (allowed: a [[plc]] name)",
                  "channel[2].name: duplicate channel name \"inflow\"",
                  "reach[0].level: unknown channel \"level\" (allowed: a [[channel]] name)",
                  "experiment[0].reach: unknown reach \"pool9\" (allowed: a [[reach]] name)"));
}

TEST(DaemonConfigTest, ReachChannelsNeedTheirRolesAndAWritableActuatorOnOnePlc) {
  DaemonConfig c = ValidConfig();
  c.channels[3].writable = false;            // the actuator
  c.channels[0].role = ChannelRole::kLevel;  // the inflow
  PlcConfig& other = c.plcs.emplace_back(c.plcs[0]);
  other.name = "plc2";
  c.channels[1].plc = "plc2";  // the outflow
  EXPECT_THAT(
      Problems(c),
      ElementsAre(
          "reach[0].inflow: channel \"inflow\" has role \"level\" (allowed: \"flow\")",
          "reach[0].actuator: channel \"gate\" is not writable (allowed: writable = true)",
          "reach[0].outflow: channel \"outflow\" is on plc \"plc2\" (allowed: the level's plc "
          "\"plc1\")"));
}

TEST(DaemonConfigTest, Ranges) {
  DaemonConfig c = ValidConfig();
  c.daemon.time_scale = 0.0;
  c.plcs[0].port = 70000;
  c.plcs[0].poll_period_s = 0.1;  // not above the response timeout
  c.channels[2].address = 65535;  // f32 needs 65535 and 65536
  c.channels[2].valid_min = 3.0;
  c.channels[2].valid_max = 2.0;
  c.reaches[0].level_max_m = 1.0;
  c.reaches[0].forgetting = 1.5;
  c.experiments[0].amplitude_percent = 12.0;
  EXPECT_THAT(
      Problems(c),
      ElementsAre("daemon.time_scale: 0 is out of range (allowed: (0, 10000])",
                  "plc[0].port: 70000 is out of range (allowed: 1..65535)",
                  "plc[0].poll_period_s: 0.1 is out of range (allowed: (0.1, 3600])",
                  "channel[2].address: 65535 is out of range (allowed: 0..65534)",
                  "channel[2].valid_max: 2 is out of range (allowed: >= valid_min 3)",
                  "reach[0].level_max_m: 1 is out of range (allowed: finite, > level_min_m 1.9)",
                  "reach[0].forgetting: 1.5 is out of range (allowed: (0, 1])",
                  "experiment[0].amplitude_percent: 12 is out of range (allowed: [5, 10])"));
}

TEST(DaemonConfigTest, WritableChannels) {
  DaemonConfig c = ValidConfig();
  ChannelConfig& gate = c.channels[3];
  gate.type = RegisterType::kI16;
  gate.scale = 0.0001;  // 2.0 m is 20000 counts: fits; 4 m would not
  gate.setpoint_max = 4.0;
  gate.valid_max = 5.0;
  gate.max_rate_per_s = 0.0;
  c.channels[2].writable = true;  // an input register
  c.channels[2].setpoint_max = 1.0;
  c.channels[2].max_rate_per_s = 1.0;
  EXPECT_THAT(
      Problems(c),
      ElementsAre("channel[2].writable: an input register cannot be written (allowed: register = "
                  "\"holding\")",
                  "channel[3].setpoint_max: 4 does not fit register type \"i16\" with this scale "
                  "and offset",
                  "channel[3].max_rate_per_s: 0 is out of range (allowed: > 0, inf = no limit)"));
}

TEST(DaemonConfigTest, HeartbeatMustNameAWritableHeartbeatChannel) {
  DaemonConfig c = ValidConfig();
  c.daemon.heartbeat = HeartbeatConfig{"level", 0.0};
  EXPECT_THAT(Problems(c),
              ElementsAre("daemon.heartbeat.period_s: 0 is out of range (allowed: (0, 3600])",
                          "daemon.heartbeat.channel: channel \"level\" is not a writable heartbeat "
                          "channel (allowed: role = \"heartbeat\", writable = true)"));
}

TEST(DaemonConfigTest, ExplicitExperimentsAndSeeds) {
  DaemonConfig c = ValidConfig();
  ExperimentConfig& e = c.experiments[0];
  e.mode = ExperimentMode::kExplicit;
  e.amplitude = 0.05;
  e.clock_period_s = 15.0;  // Ts = 0.2 s x 50 = 10 s: 1.5 samples
  e.order = 4;
  e.seed = 32;  // low 4 bits all zero
  EXPECT_THAT(Problems(c),
              ElementsAre("experiment[0].clock_period_s: 15 is not a whole number of samples "
                          "(allowed: n * sample time 10 s, n >= 1)",
                          "experiment[0].seed: 32 has no nonzero bit among the low 4 (the LFSR "
                          "order) (allowed: seed mod 2^4 != 0)"));
}

TEST(DaemonConfigTest, CommandsNeedAKeyFileWhenEnabled) {
  DaemonConfig c = ValidConfig();
  c.commands.enabled = true;
  c.commands.accepted = {CommandKind::kStartExperiment, CommandKind::kStartExperiment};
  EXPECT_THAT(Problems(c),
              ElementsAre("commands.key_file: \"\" is not an absolute path (allowed: /..., "
                          "required when enabled)",
                          "commands.accepted[1]: duplicate command \"start_experiment\""));
}

TEST(DaemonConfigTest, OneWriterPerRegisterAndOneAutomaticExperimentPerReach) {
  DaemonConfig c = ValidConfig();
  ChannelConfig& copy = c.channels.emplace_back(c.channels[3]);  // the gate, f32 at 300-301
  copy.name = "gate_low_word";
  copy.address = 301;
  copy.type = RegisterType::kU16;
  c.experiments[0].start = ExperimentStart::kOnStart;
  ExperimentConfig& second = c.experiments.emplace_back(c.experiments[0]);
  second.name = "prbs2";
  EXPECT_THAT(Problems(c),
              ElementsAre("channel[4].address: 301 overlaps writable channel \"gate\" (allowed: "
                          "one writer per register)",
                          "experiment[1].start: experiment \"prbs\" already starts reach "
                          "\"pool2\" on start (allowed: one per reach)"));
  c.channels[4].address = 302;  // next to it: fine
  c.experiments[1].start = ExperimentStart::kManual;
  EXPECT_THAT(Problems(c), IsEmpty());
}

// ValidConfig with the pool's offtake as a reach with no model, and the pool's experiment running
// the offtake's PRBS with it (a two-structure experiment).
DaemonConfig TwoStructureConfig() {
  DaemonConfig c = ValidConfig();
  const ChannelConfig gate = c.channels[3];  // copied first: emplace_back may move the vector
  ChannelConfig& offtake = c.channels.emplace_back(gate);
  offtake.name = "offtake";
  offtake.role = ChannelRole::kPump;
  offtake.address = 302;
  offtake.setpoint_min = 0.0;
  offtake.setpoint_max = 3.0;
  offtake.max_rate_per_s = 0.01;
  const ReachConfig pool = c.reaches[0];
  ReachConfig& reach = c.reaches.emplace_back(pool);
  reach.name = "pool2_offtake";
  reach.actuator = "offtake";
  reach.online_models.clear();
  reach.batch_models.clear();
  ExperimentConfig& prbs = c.experiments.emplace_back();
  prbs.name = "offtake_prbs";
  prbs.reach = "pool2_offtake";
  prbs.mode = ExperimentMode::kExplicit;
  prbs.amplitude = 0.5;
  prbs.clock_period_s = 50.0;
  prbs.seed = 77;
  c.experiments[0].with = {"offtake_prbs"};
  return c;
}

TEST(DaemonConfigTest, AJointExperimentAndAReachWithNoModel) {
  EXPECT_THAT(Problems(TwoStructureConfig()), IsEmpty());
  // Without the joint experiment, the reach with no model does nothing.
  DaemonConfig alone = TwoStructureConfig();
  alone.experiments[0].with.clear();
  EXPECT_THAT(
      Problems(alone),
      ElementsAre("reach[1].batch_models: is empty and so is online_models: the reach does "
                  "nothing (allowed: at least one of id, idz, foptd, frac-foptd, soptd, arx, "
                  "frac-ss, or none when an experiment of the reach runs `with` another "
                  "reach's)"));
  // An online model without a batch one is still an error.
  DaemonConfig online = TwoStructureConfig();
  online.reaches[1].online_models = {OnlineModel::kIntegratorDelay};
  EXPECT_THAT(Problems(online), ElementsAre(::testing::StartsWith("reach[1].batch_models: is empty "
                                                                  "(allowed: at least one of")));
}

TEST(DaemonConfigTest, JointExperimentsNeedUncorrelatedManualPartnersOfOtherActuators) {
  DaemonConfig c = TwoStructureConfig();
  c.experiments[0].with = {"nope", "prbs", "offtake_prbs"};
  // The leader's design is of order 4 (Ts 10 s, delay 682 s): 17 = 0b10001 starts that register
  // as its seed 1 does.
  c.experiments[1].order = 4;
  c.experiments[1].seed = 17;
  c.experiments[1].start = ExperimentStart::kOnStart;
  EXPECT_THAT(
      Problems(c),
      ElementsAre("experiment[0].with[0]: unknown experiment \"nope\" (allowed: an [[experiment]] "
                  "name)",
                  "experiment[0].with[1]: experiment \"prbs\" is of the same reach \"pool2\" "
                  "(allowed: an experiment of another reach)",
                  "experiment[0].with[2]: experiment \"offtake_prbs\" starts on its own (allowed: "
                  "start = \"manual\"; it starts with \"prbs\")",
                  "experiment[0].with[2]: experiment \"offtake_prbs\" starts its LFSR of order 4 "
                  "as this one does (seeds 17 and 1) (allowed: another seed in the low 4 bits, so "
                  "that the two PRBS are uncorrelated)"));
  // Another order, or another start in the low bits: uncorrelated.
  c.experiments[0].with = {"offtake_prbs"};
  c.experiments[1].start = ExperimentStart::kManual;
  c.experiments[1].order = 5;
  EXPECT_THAT(Problems(c), IsEmpty());
  c.experiments[1].order = 4;
  c.experiments[1].seed = 18;
  EXPECT_THAT(Problems(c), IsEmpty());
  // No chains, one experiment per partner reach, and never the leader's own actuator.
  DaemonConfig chain = TwoStructureConfig();
  chain.experiments[1].with = {"prbs"};
  chain.reaches[1].actuator = "gate";
  const ExperimentConfig partner = chain.experiments[1];
  ExperimentConfig& again = chain.experiments.emplace_back(partner);
  again.name = "offtake_prbs2";
  again.with.clear();
  chain.experiments[0].with = {"offtake_prbs", "offtake_prbs2"};
  EXPECT_THAT(
      Problems(chain),
      ElementsAre("experiment[0].with[0]: experiment \"offtake_prbs\" runs others with it "
                  "(allowed: one without `with`; joint experiments do not chain)",
                  "experiment[0].with[0]: experiment \"offtake_prbs\" moves this experiment's "
                  "actuator \"gate\" (allowed: an experiment of a reach with another actuator)",
                  "experiment[0].with[1]: experiment \"offtake_prbs2\" is a second one of reach "
                  "\"pool2_offtake\" (allowed: one experiment per reach)",
                  "experiment[0].with[1]: experiment \"offtake_prbs2\" moves this experiment's "
                  "actuator \"gate\" (allowed: an experiment of a reach with another actuator)",
                  "experiment[1].with[0]: experiment \"prbs\" runs others with it (allowed: one "
                  "without `with`; joint experiments do not chain)",
                  "experiment[1].with[0]: experiment \"prbs\" moves this experiment's actuator "
                  "\"gate\" (allowed: an experiment of a reach with another actuator)"));
}

TEST(DaemonPlanTest, JointExperimentsOverTheCallersReaches) {
  const DaemonConfig c = TwoStructureConfig();
  const std::vector<core::JointExperiment> all =
      BuildJointExperiments(c, {"pool2", "pool2_offtake"});
  ASSERT_EQ(all.size(), 1U);
  EXPECT_EQ(all[0].leader.reach, 0U);
  EXPECT_EQ(all[0].leader.experiment, "prbs");
  ASSERT_EQ(all[0].partners.size(), 1U);
  EXPECT_EQ(all[0].partners[0].reach, 1U);
  EXPECT_EQ(all[0].partners[0].experiment, "offtake_prbs");
  // A replay of one reach: the leader alone, or nothing when only the partner is run.
  const std::vector<core::JointExperiment> leader = BuildJointExperiments(c, {"pool2"});
  ASSERT_EQ(leader.size(), 1U);
  EXPECT_TRUE(leader[0].partners.empty());
  EXPECT_TRUE(BuildJointExperiments(c, {"pool2_offtake"}).empty());
}

TEST(DaemonConfigTest, NamesEndLcmChannelNames) {
  DaemonConfig c = ValidConfig();
  c.experiments[0].name = "pool2.prbs";
  c.channels[0].name = std::string(65, 'x');
  c.reaches[0].inflow = c.channels[0].name;
  EXPECT_THAT(Problems(c),
              ElementsAre("channel[0].name: \"" + std::string(65, 'x') +
                              "\" is not a valid name (allowed: 1 to 64 of A-Z a-z 0-9 _)",
                          "experiment[0].name: \"pool2.prbs\" is not a valid name (allowed: 1 to "
                          "64 of A-Z a-z 0-9 _)"));
}

TEST(DaemonConfigTest, DelayBankIsBoundedInSamples) {
  DaemonConfig c = ValidConfig();
  c.reaches[0].max_delay_s = 20010.0;  // Ts = 10 s: 2001 samples
  EXPECT_THAT(Problems(c), ElementsAre("reach[0].max_delay_s: 20010 is out of range (allowed: "
                                       "[min_delay_s 0, 20000], 2000 samples)"));
}

// The design rules give, for Ts = 10 s and a delay of 682 s: clock round(682 / 2 / 10) = 34
// samples; 5 x 682 = 3410 s needs (2^n - 1) x 340 s >= 3410 s, so n = 4 and 15 x 34 = 510 samples.
TEST(DaemonPlanTest, DesignedExperimentInSamplesOfThePlc) {
  const DaemonConfig c = ValidConfig();
  const ExperimentPlan plan = BuildExperimentPlan(c, c.experiments[0], 0.8);
  EXPECT_EQ(plan.prbs.clock_period_samples, 34);
  EXPECT_EQ(plan.prbs.order, 4);
  EXPECT_EQ(plan.excite_samples, 510);
  EXPECT_EQ(plan.settle_samples, 60);  // 600 s / 10 s
  EXPECT_DOUBLE_EQ(plan.prbs.nominal, 0.8);
  EXPECT_DOUBLE_EQ(plan.prbs.amplitude, 0.075 * 0.8);  // proportional: 7.5 % of the opening
  EXPECT_DOUBLE_EQ(plan.level_min_m, 1.9);
  EXPECT_DOUBLE_EQ(plan.level_max_m, 2.3);
  EXPECT_EQ(plan.max_invalid_samples, 3);
  EXPECT_EQ(plan.prbs.seed, 1u);
}

// Samples carry the poll's wall time: the gap bound is in poll periods (0.2 wall s here), not in
// plant seconds (Ts = 0.2 x 50 = 10 s).
TEST(DaemonPlanTest, SampleGapBoundIsInPollPeriodsOfWallTime) {
  DaemonConfig c = ValidConfig();
  EXPECT_DOUBLE_EQ(c.experiments[0].max_sample_gap_periods, 1.5);
  EXPECT_DOUBLE_EQ(BuildExperimentPlan(c, c.experiments[0], 0.8).max_sample_gap_s, 0.3);
  c.experiments[0].max_sample_gap_periods = 4.0;
  EXPECT_DOUBLE_EQ(BuildExperimentPlan(c, c.experiments[0], 0.8).max_sample_gap_s, 0.8);
  c.experiments[0].max_sample_gap_periods = 1.0;
  EXPECT_THAT(Problems(c), ElementsAre("experiment[0].max_sample_gap_periods: 1 is out of range "
                                       "(allowed: [1.1, 1000])"));
}

TEST(DaemonPlanTest, DesignOfAnExperimentExplainsItself) {
  DaemonConfig c = ValidConfig();
  const ExperimentDesign design = DesignExperiment(c, c.experiments[0]);
  EXPECT_DOUBLE_EQ(design.amplitude_m3s, 0.75);  // 7.5 % of 10 m3/s
  EXPECT_DOUBLE_EQ(design.clock_period_s, 340.0);
  EXPECT_FALSE(design.explanation.empty());
  c.experiments[0].mode = ExperimentMode::kExplicit;
  EXPECT_THROW(DesignExperiment(c, c.experiments[0]), std::invalid_argument);
}

TEST(DaemonPlanTest, DesignWithAnActuatorGain) {
  DaemonConfig c = ValidConfig();
  c.reaches[0].actuator_gain_m3s_per_unit = -15.0;  // sign does not matter for an amplitude
  const ExperimentPlan plan = BuildExperimentPlan(c, c.experiments[0], 0.8);
  EXPECT_DOUBLE_EQ(plan.prbs.amplitude, 0.75 / 15.0);  // 7.5 % of 10 m3/s, in metres of opening
}

TEST(DaemonPlanTest, ExplicitExperiment) {
  DaemonConfig c = ValidConfig();
  ExperimentConfig& e = c.experiments[0];
  e.mode = ExperimentMode::kExplicit;
  e.amplitude = 0.05;
  e.clock_period_s = 360.0;
  e.order = 5;
  e.periods = 2;
  e.settle_s = 595.0;  // rounds up to 60 samples
  const ExperimentPlan plan = BuildExperimentPlan(c, e, 0.8);
  EXPECT_EQ(plan.prbs.clock_period_samples, 36);
  EXPECT_EQ(plan.excite_samples, 2 * 31 * 36);
  EXPECT_EQ(plan.settle_samples, 60);
  EXPECT_DOUBLE_EQ(plan.prbs.amplitude, 0.05);
  // The seed's low `order` bits start the register (docs/configuration.md): 77 = 0b1001101 starts
  // an order-5 LFSR at 0b01101 = 13 (the plan used to keep 77, which the LFSR refused).
  e.seed = 77;
  EXPECT_THAT(Problems(c), IsEmpty());
  const ExperimentPlan masked = BuildExperimentPlan(c, e, 0.8);
  EXPECT_EQ(masked.prbs.seed, 13U);
  EXPECT_NO_THROW(masked.Validate());
}

TEST(DaemonPlanTest, StepExperiment) {
  DaemonConfig c = ValidConfig();
  ExperimentConfig& e = c.experiments[0];
  e.mode = ExperimentMode::kStep;
  e.amplitude = 0.05;
  e.hold_s = 3600.0;  // Ts = 0.2 x 50 = 10 s: 360 samples
  EXPECT_THAT(Problems(c), IsEmpty());
  const ExperimentPlan plan = BuildExperimentPlan(c, e, 0.8);
  EXPECT_EQ(plan.step_hold_samples, 360);
  EXPECT_EQ(plan.excite_samples, 720);
  EXPECT_DOUBLE_EQ(plan.prbs.amplitude, 0.05);
  e.hold_s = 3605.0;  // not a whole number of samples
  EXPECT_THAT(Problems(c), ElementsAre("experiment[0].hold_s: 3605 is not a whole number of "
                                       "samples (allowed: n * sample time 10 s, n >= 1)"));
  // A step covers [nominal, nominal + amplitude]: from just above setpoint_min (0.05) it fits,
  // where a PRBS of the same amplitude would go below the range.
  e.hold_s = 3600.0;
  EXPECT_EQ(BuildExperimentPlan(c, e, 0.06).step_hold_samples, 360);
  e.mode = ExperimentMode::kExplicit;
  e.clock_period_s = 360.0;
  EXPECT_THROW(BuildExperimentPlan(c, e, 0.06), std::invalid_argument);
  e.mode = ExperimentMode::kStep;
  try {
    BuildExperimentPlan(c, e, 1.98);
    ADD_FAILURE() << "a step above setpoint_max was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("+ step 0.05"), std::string::npos) << error.what();
  }
  e.hold_s = 3600.0;
  e.amplitude = 0.0;
  EXPECT_THAT(Problems(c),
              ElementsAre("experiment[0].amplitude: 0 is out of range (allowed: > 0, finite)"));
}

TEST(DaemonPlanTest, AmplitudeMustStayInsideTheActuatorRange) {
  DaemonConfig c = ValidConfig();
  EXPECT_THROW(BuildExperimentPlan(c, c.experiments[0], 1.98), std::invalid_argument);
  EXPECT_THROW(BuildExperimentPlan(c, c.experiments[0], 0.0), std::invalid_argument);
}

TEST(DaemonPlanTest, OnlineIntegratorDelayOptions) {
  DaemonConfig c = ValidConfig();
  c.reaches[0].min_delay_s = 300.0;
  c.reaches[0].forgetting = 0.999;
  c.reaches[0].rls_method = RlsMethod::kDirectional;
  const OnlineIntegratorDelayOptions o = BuildOnlineIntegratorDelayOptions(c, c.reaches[0]);
  EXPECT_DOUBLE_EQ(o.sample_time_s, 10.0);
  EXPECT_EQ(o.min_delay_samples, 30);
  EXPECT_EQ(o.max_delay_samples, 140);
  EXPECT_EQ(o.rls.method, RlsMethod::kDirectional);
  EXPECT_DOUBLE_EQ(o.rls.forgetting, 0.999);
}

// The PLC of a reach is the PLC of its level channel, the one lookup the daemon, replay and the
// sample time share.
TEST(DaemonConfigTest, ReachPlcIsThePlcOfItsLevelChannel) {
  DaemonConfig c = ValidConfig();
  PlcConfig& other = c.plcs.emplace_back(c.plcs[0]);
  other.name = "plc2";
  other.poll_period_s = 0.5;
  EXPECT_EQ(c.FindReachPlc(c.reaches[0]), &c.plcs[0]);
  c.channels[2].plc = "plc2";  // the level
  EXPECT_EQ(c.FindReachPlc(c.reaches[0]), &c.plcs[1]);
  EXPECT_DOUBLE_EQ(ReachSampleTimeS(c, c.reaches[0]), 25.0);
  c.channels[2].plc = "nowhere";
  EXPECT_EQ(c.FindReachPlc(c.reaches[0]), nullptr);
  EXPECT_THROW(ReachSampleTimeS(c, c.reaches[0]), std::invalid_argument);
  c.reaches[0].level = "missing";
  EXPECT_EQ(c.FindReachPlc(c.reaches[0]), nullptr);
}

}  // namespace
}  // namespace canalid::config
