// DecideRestart: each start-up rule on an interrupted experiment's guard; the reach controller
// that applies the decision (restore first, hold, refuse, never a PRBS reading as the nominal); the
// abort on a guard not persisted; the restore safety the controller keeps (a restore asked again
// until the PLC confirms that value, when the guard is removed or kept, an operator's start
// refused); the stop's wait; and the decision `canalid replay` rebuilds from the message.
#include "core/experiment/experiment_guard.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "core/reach/reach_controller.h"
#include "core/reach/stop_rule.h"

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
  o.experiments.push_back({"pool2-prbs",
                           [](double nominal) {
                             ExperimentPlan plan;
                             plan.prbs.nominal = nominal;
                             plan.prbs.amplitude = 0.05;
                             plan.prbs.clock_period_samples = 2;
                             plan.prbs.order = 4;
                             plan.excite_samples = 30;
                             plan.level_min_m = 1.5;
                             plan.level_max_m = 2.7;
                             return plan;
                           },
                           true});
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
  EXPECT_EQ(poll.actions.write_setpoint, 1.532637);  // the restore, written first
  EXPECT_TRUE(poll.actions.restore_nominal);
  EXPECT_FALSE(runner.excitation_allowed());
  EXPECT_FALSE(runner.StartIfDue(true, true));  // held until the restore is confirmed
  runner.OnWriteQueued(1);
  EXPECT_TRUE(runner.OnWriteResult({true, 1.532637, 1}).restore_confirmed);
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
  EXPECT_FALSE(poll.actions.write_setpoint);  // no nominal known: nothing to restore
  runner.OnWriteQueued(1);
  EXPECT_FALSE(runner.OnWriteResult({true, 1.417689, 1}).restore_confirmed);
  EXPECT_FALSE(runner.excitation_allowed());
  EXPECT_FALSE(runner.StartIfDue(true, true));
}

TEST(ReachSampleProcessorGuard, AGuardNotPersistedAbortsAndRestoresTheNominal) {
  ReachController runner(RunnerOptions());
  runner.OnPoll(Readings(1.2));
  ASSERT_TRUE(runner.StartIfDue(true, true));
  const ReachActions a = runner.OnGuardNotPersisted();
  EXPECT_EQ(runner.pipeline().experiment_state().phase, ExperimentPhase::kAborted);
  EXPECT_EQ(runner.pipeline().experiment_state().abort_reason, AbortReason::kGuardNotPersisted);
  EXPECT_STREQ(AbortReasonName(AbortReason::kGuardNotPersisted), "experiment guard not persisted");
  ASSERT_TRUE(a.write_setpoint);
  EXPECT_EQ(*a.write_setpoint, 1.2);
  EXPECT_TRUE(a.restore_nominal);
  // The excitation write that needed the guard superseded nothing: the abort's restore is pending.
  EXPECT_EQ(runner.restore_pending(), 1.2);
  // Not running: nothing to abort.
  EXPECT_FALSE(runner.OnGuardNotPersisted().write_setpoint);
}

// ----- the restore safety the controller keeps (reach_controller.h) -----------------------------

ReachReadings LinkDown(double time_s) {
  ReachReadings r;
  r.link_ok = false;
  r.status_ok = false;
  r.time_s = time_s;
  return r;
}

// Write ids as the daemon's poller hands them out: Queue() tells the controller that the write of
// its last actions was queued and returns the write's id.
class WriteIds {
 public:
  std::uint64_t Queue(ReachController& runner) {
    runner.OnWriteQueued(next_);
    return next_++;
  }

 private:
  std::uint64_t next_ = 1;
};

// RunnerOptions with `settle_samples` of settling before each experiment's excitation.
ReachControllerOptions SettlingOptions(std::int64_t settle_samples) {
  ReachControllerOptions options = RunnerOptions();
  auto& plan_for = options.experiments.front().plan_for_nominal;
  plan_for = [settle_samples, first = plan_for](double nominal) {
    ExperimentPlan plan = first(nominal);
    plan.settle_samples = settle_samples;
    return plan;
  };
  return options;
}

// A controller whose experiment around 1.2 (with RunnerOptions' 30 exciting samples, settling
// `settle_samples` first) is running, its guard persisted, every write so far queued in `ids`.
ReachController Running(WriteIds& ids, std::int64_t settle_samples = 0) {
  ReachController runner(SettlingOptions(settle_samples));
  runner.OnPoll(Readings(1.2));
  const auto start = runner.StartIfDue(true, true);
  EXPECT_TRUE(start);
  ids.Queue(runner);
  for (std::int64_t k = 0; k < settle_samples; ++k) runner.OnPoll(Readings(1.2));
  EXPECT_EQ(runner.pipeline().experiment_state().phase, ExperimentPhase::kExciting);
  runner.OnGuardPersisted();
  return runner;
}

TEST(ReachControllerRestoreSafety, APendingRestoreIsAskedAgainOnEveryPollUntilTheValueIsConfirmed) {
  WriteIds ids;
  ReachController runner = Running(ids);
  const ReachActions stop = runner.Stop();
  EXPECT_EQ(stop.write_setpoint, 1.2);
  EXPECT_EQ(runner.restore_pending(), 1.2);
  ids.Queue(runner);
  // Every poll with the link up asks for it again; one with the link down does not.
  for (int i = 0; i < 3; ++i) {
    const ReachActions again = runner.OnPoll(Readings(1.25)).actions;
    EXPECT_EQ(again.write_setpoint, 1.2) << i;
    EXPECT_TRUE(again.restore_nominal) << i;
    EXPECT_FALSE(runner.needs_guard(again)) << i;  // a restore never waits for the guard
    ids.Queue(runner);
  }
  EXPECT_FALSE(runner.OnPoll(LinkDown(0.0)).actions.write_setpoint);
  // Neither another value written nor a failed write confirms it.
  EXPECT_FALSE(runner.OnWriteResult({true, 1.25, ids.Queue(runner)}).restore_confirmed);
  EXPECT_FALSE(runner.OnWriteResult({true, 1.2 + 1e-6, ids.Queue(runner)}).restore_confirmed);
  const ReachWriteOutcome failed = runner.OnWriteResult({false, 1.2, ids.Queue(runner)});
  EXPECT_FALSE(failed.restore_confirmed);
  EXPECT_FALSE(failed.actions.write_setpoint);  // nothing running to abort
  EXPECT_EQ(runner.restore_pending(), 1.2);
  // The PLC confirms 1.2: nothing more is asked, and the guard has done its job.
  const ReachWriteOutcome confirmed = runner.OnWriteResult({true, 1.2, ids.Queue(runner)});
  EXPECT_TRUE(confirmed.restore_confirmed);
  EXPECT_TRUE(confirmed.remove_guard);
  EXPECT_FALSE(runner.restore_pending());
  EXPECT_FALSE(runner.OnPoll(Readings(1.2)).actions.write_setpoint);
  // A second confirmation removes nothing twice, and the next experiment needs a guard again.
  EXPECT_FALSE(runner.OnWriteResult({true, 1.2, ids.Queue(runner)}).remove_guard);
  EXPECT_TRUE(runner.needs_guard(runner.Start()));
}

TEST(ReachControllerRestoreSafety, TheEndOfTheExcitationRestoresAndThenRemovesTheGuard) {
  WriteIds ids;
  ReachController runner = Running(ids);
  ReachActions end;
  for (int k = 0; k < 30 && !end.restore_nominal; ++k) {
    end = runner.OnPoll(Readings(1.2)).actions;
    ids.Queue(runner);
  }
  ASSERT_TRUE(end.restore_nominal);
  EXPECT_EQ(end.write_setpoint, 1.2);
  ASSERT_TRUE(end.experiment_record_complete);
  ReachActions after;
  runner.IdentifyRecord(&after);  // done or aborted: either way not settling or exciting
  const ReachWriteOutcome confirmed = runner.OnWriteResult({true, 1.2, ids.Queue(runner)});
  EXPECT_TRUE(confirmed.restore_confirmed);
  EXPECT_TRUE(confirmed.remove_guard);
}

TEST(ReachControllerRestoreSafety, AFailedWriteDuringAnExperimentAbortsAndRestores) {
  WriteIds ids;
  ReachController runner = Running(ids);
  const ReachWriteOutcome failed = runner.OnWriteResult({false, 1.25, 1});
  EXPECT_EQ(runner.pipeline().experiment_state().abort_reason, AbortReason::kWriteFailed);
  EXPECT_EQ(failed.actions.write_setpoint, 1.2);
  EXPECT_TRUE(failed.actions.restore_nominal);
  EXPECT_EQ(runner.restore_pending(), 1.2);
}

TEST(ReachControllerRestoreSafety, TheLinkLostBetweenPollsAbortsAndRestoresOnceItIsBack) {
  WriteIds ids;
  ReachController runner = Running(ids);
  const ReachActions lost = runner.OnLinkLost();
  EXPECT_EQ(runner.pipeline().experiment_state().abort_reason, AbortReason::kLinkLost);
  EXPECT_EQ(runner.restore_pending(), 1.2);
  EXPECT_EQ(lost.write_setpoint, 1.2);  // queued: the poller writes it once it reconnects
  EXPECT_EQ(runner.OnPoll(Readings(1.25)).actions.write_setpoint, 1.2);
}

TEST(ReachControllerRestoreSafety, AnExcitationWriteSupersedesAPendingRestore) {
  WriteIds ids;
  ReachController runner = Running(ids);
  runner.Stop();
  const std::uint64_t stop_write = ids.Queue(runner);
  // An operator starts again (no settling) before the PLC has answered the stop's restore.
  const ReachActions start = runner.Start();
  ASSERT_TRUE(start.write_setpoint);
  EXPECT_FALSE(start.restore_nominal);
  EXPECT_FALSE(runner.restore_pending());
  ids.Queue(runner);
  const ReachWriteOutcome late = runner.OnWriteResult({true, 1.2, stop_write});
  EXPECT_FALSE(late.restore_confirmed);
  EXPECT_FALSE(late.remove_guard);  // the running experiment's guard
  EXPECT_FALSE(runner.needs_guard(start));
  // The next poll writes the PRBS's next level, not the nominal.
  const ReachActions next = runner.OnPoll(Readings(1.25)).actions;
  ASSERT_TRUE(next.write_setpoint);
  EXPECT_FALSE(next.restore_nominal);
  EXPECT_NEAR(std::abs(*next.write_setpoint - 1.2), 0.05, 1e-12);
}

TEST(ReachControllerRestoreSafety, AnOlderWriteOfTheSameValueNeverConfirmsANewerRestore) {
  // Stop (restore 1.2), start (a PRBS level), stop again, all before the PLC answers: the first
  // stop's write, of the same nominal, was followed by the PRBS level and confirms nothing.
  WriteIds ids;
  ReachController runner = Running(ids);
  runner.Stop();
  const std::uint64_t first_stop = ids.Queue(runner);
  runner.Start();
  ids.Queue(runner);
  runner.Stop();
  const std::uint64_t second_stop = ids.Queue(runner);
  EXPECT_FALSE(runner.OnWriteResult({true, 1.2, first_stop}).restore_confirmed);
  EXPECT_EQ(runner.restore_pending(), 1.2);
  EXPECT_EQ(runner.OnPoll(Readings(1.25)).actions.write_setpoint, 1.2);  // still asked
  const ReachWriteOutcome confirmed = runner.OnWriteResult({true, 1.2, second_stop});
  EXPECT_TRUE(confirmed.restore_confirmed);
  EXPECT_TRUE(confirmed.remove_guard);
  // A restore with no write queued yet (the queue refused it) is confirmed by nothing.
  runner.Start();
  ids.Queue(runner);
  runner.Stop();
  EXPECT_FALSE(runner.OnWriteResult({true, 1.2, second_stop}).restore_confirmed);
  EXPECT_EQ(runner.restore_pending(), 1.2);
}

TEST(ReachControllerRestoreSafety, AConfirmationWhileANewExperimentSettlesKeepsItsGuard) {
  WriteIds ids;
  ReachController runner = Running(ids, /*settle_samples=*/3);
  runner.Stop();
  ids.Queue(runner);
  // Started again: settling writes the nominal, as a restore.
  const ReachActions start = runner.Start();
  EXPECT_EQ(start.write_setpoint, 1.2);
  EXPECT_TRUE(start.restore_nominal);
  const ReachWriteOutcome confirmed = runner.OnWriteResult({true, 1.2, ids.Queue(runner)});
  EXPECT_TRUE(confirmed.restore_confirmed);
  EXPECT_FALSE(confirmed.remove_guard);  // the settling experiment excites next
}

TEST(ReachControllerRestoreSafety, AStopWhileSettlingHasNoGuardToRemove) {
  WriteIds ids;
  ReachController runner(SettlingOptions(3));
  runner.OnPoll(Readings(1.2));
  const auto start = runner.StartIfDue(true, true);
  ASSERT_TRUE(start);
  EXPECT_FALSE(runner.needs_guard(*start));  // settling writes the nominal: no guard yet
  ids.Queue(runner);
  runner.Stop();
  const ReachWriteOutcome confirmed = runner.OnWriteResult({true, 1.2, ids.Queue(runner)});
  EXPECT_TRUE(confirmed.restore_confirmed);
  EXPECT_FALSE(confirmed.remove_guard);
}

TEST(ReachControllerRestoreSafety, ARefusedStartUpRestoresTheConfiguredNominalAndKeepsTheGuard) {
  ReachControllerOptions options = RunnerOptions();
  options.nominal_setpoint = 0.9;
  WriteIds ids;
  ReachController runner(options);
  EXPECT_EQ(runner.ApplyRestart(DecideRestart(Context(0.9), Corrupt())), "");
  EXPECT_EQ(runner.restore_pending(), 0.9);
  EXPECT_EQ(runner.OnPoll(Readings(1.417689)).actions.write_setpoint, 0.9);
  const ReachWriteOutcome confirmed = runner.OnWriteResult({true, 0.9, ids.Queue(runner)});
  EXPECT_TRUE(confirmed.restore_confirmed);
  EXPECT_FALSE(confirmed.remove_guard);  // for an operator to check
  EXPECT_FALSE(runner.excitation_allowed());
  EXPECT_NE(runner.StartRefusal(), "");
  EXPECT_FALSE(runner.StartIfDue(true, true));
}

TEST(ReachControllerRestoreSafety, AnOperatorsStartIsRefusedWithoutAPlanOrBeforeTheRestore) {
  ReachControllerOptions none = RunnerOptions();
  none.experiments.clear();
  ReachController no_plan(none);
  no_plan.OnPoll(Readings(1.2));
  EXPECT_EQ(no_plan.StartRefusal(), "no experiment to start");
  WriteIds ids;
  ReachController held(RunnerOptions());
  held.ApplyRestart(DecideRestart(Context(), Found(1.2)));
  EXPECT_NE(held.StartRefusal().find("not restored"), std::string::npos) << held.StartRefusal();
  held.OnWriteResult({true, 1.2, ids.Queue(held)});
  EXPECT_EQ(held.StartRefusal(), "");
}

TEST(DecideStop, WaitsForEveryRestoreUntilTheDeadline) {
  EXPECT_EQ(DecideStop(false, 10.0, 5.0), StopProgress::kSafe);
  EXPECT_EQ(DecideStop(false, 1.0, 5.0), StopProgress::kSafe);
  EXPECT_EQ(DecideStop(true, 4.999, 5.0), StopProgress::kWait);
  EXPECT_EQ(DecideStop(true, 5.0, 5.0), StopProgress::kDeadlinePassed);
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
