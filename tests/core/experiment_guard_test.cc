// DecideRestart: each start-up rule on an interrupted experiment's guard; the reach runner that
// applies the decision (restore first, hold, refuse, never a PRBS reading as the nominal); the
// abort on a guard not persisted; and the decision `canalid replay` rebuilds from the message.
#include "core/experiment/experiment_guard.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/reach/reach_controller.h"

namespace canalid::core {
namespace {

RestartContext Context(std::optional<double> configured = std::nullopt) {
  RestartContext c;
  c.reach = "pool2";
  c.actuator = "gate1_setpoint";
  c.setpoint_min = 0.05;
  c.setpoint_max = 2.0;
  c.configured_nominal = configured;
  return c;
}

GuardReading Found(double nominal, const std::string& actuator = "gate1_setpoint",
                   const std::string& reach = "pool2") {
  GuardReading r;
  r.kind = GuardReading::Kind::kFound;
  r.guard.reach = reach;
  r.guard.actuator = actuator;
  r.guard.experiment = "pool2_prbs";
  r.guard.nominal_setpoint = nominal;
  r.guard.started_utime_us = 1700000000LL * 1000000LL;  // 2023-11-14T22:13:20Z
  return r;
}

GuardReading Corrupt() {
  GuardReading r;
  r.kind = GuardReading::Kind::kCorrupt;
  r.problem = "/var/lib/canalidd/pool2.experiment.json: corrupt or truncated JSON";
  return r;
}

TEST(DecideRestart, NoGuardStartsAsUsual) {
  const RestartDecision d = DecideRestart(Context(), GuardReading{});
  EXPECT_EQ(d.action, RestartDecision::Action::kNone);
  EXPECT_FALSE(d.restore_setpoint);
  EXPECT_FALSE(d.nominal);  // the first reading
  EXPECT_TRUE(d.excitation_allowed);
  EXPECT_FALSE(d.hold_until_restored);
  EXPECT_EQ(DecideRestart(Context(0.9), GuardReading{}).nominal, 0.9);
}

TEST(DecideRestart, AGuardOfThisActuatorRestoresItsNominalFirstAndHolds) {
  const RestartDecision d = DecideRestart(Context(), Found(1.532637));
  EXPECT_EQ(d.action, RestartDecision::Action::kRestore);
  EXPECT_EQ(d.restore_setpoint, 1.532637);
  EXPECT_EQ(d.nominal, 1.532637);
  EXPECT_TRUE(d.excitation_allowed);
  EXPECT_TRUE(d.hold_until_restored);
  EXPECT_FALSE(d.error);
  EXPECT_NE(d.message.find("interrupted experiment on reach pool2: restoring nominal 1.532637 "
                           "persisted at 2023-11-14T22:13:20Z"),
            std::string::npos)
      << d.message;
}

TEST(DecideRestart, AConfiguredNominalWinsForExperimentsButTheGuardsIsRestored) {
  const RestartDecision d = DecideRestart(Context(1.5), Found(1.532637));
  EXPECT_EQ(d.action, RestartDecision::Action::kRestore);
  EXPECT_EQ(d.restore_setpoint, 1.532637);
  EXPECT_EQ(d.nominal, 1.5);
  EXPECT_NE(d.message.find("configured nominal 1.5 differs"), std::string::npos) << d.message;
  EXPECT_EQ(DecideRestart(Context(1.532637), Found(1.532637)).message.find("differs"),
            std::string::npos);
}

TEST(DecideRestart, AnActuatorTheReachNoLongerHasIsRefusedWithoutAWrite) {
  const RestartDecision d = DecideRestart(Context(0.9), Found(1.2, "gate2_setpoint"));
  EXPECT_EQ(d.action, RestartDecision::Action::kRefuse);
  EXPECT_FALSE(d.excitation_allowed);
  EXPECT_FALSE(d.restore_setpoint);
  EXPECT_EQ(d.nominal, 0.9);
  EXPECT_TRUE(d.error);
  EXPECT_NE(d.message.find("gate2_setpoint"), std::string::npos) << d.message;
}

TEST(DecideRestart, ANominalOutsideTheLimitsIsRefused) {
  for (const double bad : {0.01, 2.5, std::numeric_limits<double>::quiet_NaN()}) {
    const RestartDecision d = DecideRestart(Context(), Found(bad));
    EXPECT_EQ(d.action, RestartDecision::Action::kRefuse) << bad;
    EXPECT_FALSE(d.excitation_allowed) << bad;
    EXPECT_FALSE(d.restore_setpoint) << bad;
    EXPECT_FALSE(d.nominal) << bad;
    EXPECT_TRUE(d.error) << bad;
  }
  // The limits themselves are inside.
  EXPECT_EQ(DecideRestart(Context(), Found(2.0)).action, RestartDecision::Action::kRestore);
}

TEST(DecideRestart, ACorruptGuardIsAnInterruptionWithAnUnknownNominal) {
  const RestartDecision d = DecideRestart(Context(), Corrupt());
  EXPECT_EQ(d.action, RestartDecision::Action::kRefuse);
  EXPECT_FALSE(d.excitation_allowed);
  EXPECT_FALSE(d.restore_setpoint);
  EXPECT_FALSE(d.nominal);
  EXPECT_TRUE(d.error);
  EXPECT_NE(d.message.find("pool2.experiment.json"), std::string::npos) << d.message;
  // With a configured nominal, that one is restored (and still no experiment).
  const RestartDecision c = DecideRestart(Context(0.9), Corrupt());
  EXPECT_EQ(c.restore_setpoint, 0.9);
  EXPECT_EQ(c.nominal, 0.9);
  EXPECT_FALSE(c.excitation_allowed);
  // A guard naming another reach is not trusted either.
  EXPECT_EQ(DecideRestart(Context(), Found(1.2, "gate1_setpoint", "pool3")).action,
            RestartDecision::Action::kRefuse);
}

ReachControllerOptions RunnerOptions() {
  ReachControllerOptions o;
  o.name = "pool2";
  o.channels = {0, 1, 2, 3};
  o.pipeline.sample_time_s = 60.0;
  o.pipeline.online_id_enabled = false;
  o.start_experiment_on_start = true;
  o.experiment_for_nominal = [](double nominal) {
    ExperimentPlan plan;
    plan.prbs.nominal = nominal;
    plan.prbs.amplitude = 0.05;
    plan.prbs.clock_period_samples = 2;
    plan.prbs.order = 4;
    plan.excite_samples = 30;
    plan.level_min_m = 1.5;
    plan.level_max_m = 2.7;
    return plan;
  };
  return o;
}

ReachReadings Readings(double actuator) {
  ReachReadings r;
  r.q_in_m3s = 10.0;
  r.q_out_m3s = 10.0;
  r.level_m = 2.1;
  r.actuator = actuator;
  r.q_in_valid = r.q_out_valid = r.level_valid = r.actuator_valid = true;
  return r;
}

TEST(ReachControllerRestart, RestoresFirstThenCentresTheExperimentOnThePersistedNominal) {
  ReachController runner(RunnerOptions());
  EXPECT_EQ(runner.ApplyRestart(DecideRestart(Context(), Found(1.532637))), "");
  // The actuator still holds the PRBS level: it is not the nominal.
  const ReachPollOutcome poll = runner.OnPoll(Readings(1.417689));
  EXPECT_FALSE(poll.nominal_read);
  EXPECT_EQ(runner.nominal(), 1.532637);
  EXPECT_FALSE(runner.excitation_allowed());
  EXPECT_FALSE(runner.StartIfDue(true, true));  // held until the restore is confirmed
  runner.OnRestoreConfirmed();
  EXPECT_TRUE(runner.excitation_allowed());
  const auto start = runner.StartIfDue(true, true);
  ASSERT_TRUE(start);
  ASSERT_TRUE(start->write_setpoint);
  EXPECT_NEAR(std::abs(*start->write_setpoint - 1.532637), 0.05, 1e-12);
}

TEST(ReachControllerRestart, ARefusalNeverStartsAndTakesNoReadingAsNominal) {
  ReachController runner(RunnerOptions());
  EXPECT_EQ(runner.ApplyRestart(DecideRestart(Context(), Corrupt())), "");
  const ReachPollOutcome poll = runner.OnPoll(Readings(1.417689));
  EXPECT_FALSE(poll.nominal_read);
  EXPECT_FALSE(runner.nominal_known());
  runner.OnRestoreConfirmed();
  EXPECT_FALSE(runner.excitation_allowed());
  EXPECT_FALSE(runner.StartIfDue(true, true));
}

TEST(ReachSampleProcessorGuard, AGuardNotPersistedAbortsAndRestoresTheNominal) {
  ReachController runner(RunnerOptions());
  runner.OnPoll(Readings(1.2));
  ASSERT_TRUE(runner.StartIfDue(true, true));
  const ReachActions a = runner.pipeline().OnGuardNotPersisted();
  EXPECT_EQ(runner.pipeline().experiment_state().phase, ExperimentPhase::kAborted);
  EXPECT_EQ(runner.pipeline().experiment_state().abort_reason, AbortReason::kGuardNotPersisted);
  EXPECT_STREQ(AbortReasonName(AbortReason::kGuardNotPersisted), "experiment guard not persisted");
  ASSERT_TRUE(a.write_setpoint);
  EXPECT_EQ(*a.write_setpoint, 1.2);
  EXPECT_TRUE(a.restore_nominal);
  // Not running: nothing to abort.
  EXPECT_FALSE(runner.pipeline().OnGuardNotPersisted().write_setpoint);
}

TEST(RestartDecisionFromMessage, RebuildsWhatTheDaemonDecided) {
  const auto restore = RestartDecisionFromMessage(
      std::string(kRestartRestoreReason) + " 1.532637 persisted at 2023-11-14T22:13:20Z", 1.532637,
      std::nullopt);
  ASSERT_TRUE(restore);
  EXPECT_EQ(restore->action, RestartDecision::Action::kRestore);
  EXPECT_EQ(restore->nominal, 1.532637);
  EXPECT_TRUE(restore->hold_until_restored);
  EXPECT_EQ(RestartDecisionFromMessage(kRestartRestoreReason, 1.53, 1.5)->nominal, 1.5);
  const auto refused = RestartDecisionFromMessage(std::string(kRestartRefusedReason) + ": ...",
                                                  std::nan(""), std::nullopt);
  ASSERT_TRUE(refused);
  EXPECT_FALSE(refused->excitation_allowed);
  EXPECT_FALSE(refused->nominal);
  EXPECT_FALSE(RestartDecisionFromMessage("level out of band", 1.5, std::nullopt));
  EXPECT_FALSE(RestartDecisionFromMessage(kRestartRestoreReason, std::nan(""), std::nullopt));
}

TEST(FormatUtcTime, IsoSecondsInUtc) {
  EXPECT_EQ(FormatUtcTime(1700000000LL * 1000000LL + 999999), "2023-11-14T22:13:20Z");
  EXPECT_EQ(FormatUtcTime(0), "1970-01-01T00:00:00Z");
}

}  // namespace
}  // namespace canalid::core
