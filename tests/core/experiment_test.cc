#include "core/experiment/experiment.h"

#include <gtest/gtest.h>

#include <vector>

namespace canalid::core {
namespace {

ExperimentPlan Plan() {
  ExperimentPlan plan;
  plan.prbs.nominal = 0.5;  // e.g. a gate opening, m
  plan.prbs.amplitude = 0.04;
  plan.prbs.clock_period_samples = 3;
  plan.prbs.order = 4;
  plan.prbs.seed = 5;
  plan.settle_samples = 4;
  plan.excite_samples = 45;
  plan.level_min_m = 1.9;
  plan.level_max_m = 2.3;
  plan.max_invalid_samples = 1;
  plan.Validate();
  return plan;
}

ExperimentEvent Sample(double level, bool valid = true, bool link = true) {
  ExperimentEvent e;
  e.kind = ExperimentEventKind::kSample;
  e.sample = {level, valid, link};
  return e;
}

ExperimentEvent TimedSample(double level, double time_s) {
  ExperimentEvent e = Sample(level);
  e.sample.time_s = time_s;
  return e;
}

ExperimentEvent Event(ExperimentEventKind kind) {
  ExperimentEvent e;
  e.kind = kind;
  return e;
}

// Drives the machine and keeps every transition.
struct Driver {
  ExperimentPlan plan = Plan();
  ExperimentState state;
  std::vector<ExperimentActions> actions;
  ExperimentActions Apply(const ExperimentEvent& e) {
    ExperimentTransition t = Step(plan, state, e);
    state = t.state;
    actions.push_back(t.actions);
    return t.actions;
  }
};

TEST(Experiment, RunsSettleExciteIdentifyDoneWithThePrbsOfTheDesign) {
  Driver run;
  ExperimentActions a = run.Apply(Event(ExperimentEventKind::kStart));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kSettling);
  ASSERT_TRUE(a.write_setpoint.has_value());
  EXPECT_DOUBLE_EQ(*a.write_setpoint, 0.5);
  std::vector<double> written;
  for (int k = 0; k < 4; ++k) {
    a = run.Apply(Sample(2.1));
    EXPECT_FALSE(a.record_sample);
    if (a.write_setpoint) written.push_back(*a.write_setpoint);
  }
  EXPECT_EQ(run.state.phase, ExperimentPhase::kExciting);
  int recorded = 0;
  while (run.state.phase == ExperimentPhase::kExciting) {
    a = run.Apply(Sample(2.1));
    recorded += a.record_sample;
    if (a.write_setpoint && !a.restore_nominal) written.push_back(*a.write_setpoint);
  }
  EXPECT_EQ(recorded, 45);
  EXPECT_EQ(run.state.phase, ExperimentPhase::kIdentifying);
  EXPECT_TRUE(a.start_identification);
  EXPECT_TRUE(a.restore_nominal);
  EXPECT_DOUBLE_EQ(*a.write_setpoint, 0.5);
  // Exactly the designed signal, one value per recorded sample.
  const Eigen::VectorXd expected = GeneratePrbs(run.plan.prbs, 45);
  ASSERT_EQ(written.size(), 45U);
  for (int k = 0; k < 45; ++k)
    EXPECT_DOUBLE_EQ(written[static_cast<std::size_t>(k)], expected(k)) << k;
  run.Apply(Event(ExperimentEventKind::kIdentificationSucceeded));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kDone);
}

TEST(Experiment, EveryFaultAbortsAndRestoresNominalInTheSameTransition) {
  struct Case {
    ExperimentEvent event;
    AbortReason reason;
  };
  const std::vector<Case> cases = {
      {Sample(2.31), AbortReason::kLevelOutOfBand},
      {Sample(1.89), AbortReason::kLevelOutOfBand},
      {Sample(2.1, true, false), AbortReason::kLinkLost},
      {Event(ExperimentEventKind::kWriteFailed), AbortReason::kWriteFailed},
      {Event(ExperimentEventKind::kStop), AbortReason::kOperatorStop},
      {Event(ExperimentEventKind::kJointStop), AbortReason::kJointStop},
  };
  for (const Case& c : cases) {
    for (int warmup : {2, 9}) {  // while settling, and while exciting
      Driver run;
      run.Apply(Event(ExperimentEventKind::kStart));
      for (int k = 0; k < warmup; ++k) run.Apply(Sample(2.1));
      const ExperimentActions a = run.Apply(c.event);
      EXPECT_EQ(run.state.phase, ExperimentPhase::kAborted);
      EXPECT_EQ(run.state.abort_reason, c.reason) << AbortReasonName(c.reason);
      EXPECT_TRUE(a.restore_nominal);
      ASSERT_TRUE(a.write_setpoint.has_value());
      EXPECT_DOUBLE_EQ(*a.write_setpoint, 0.5);
      // Nothing moves the actuator after an abort.
      for (int k = 0; k < 5; ++k) EXPECT_FALSE(run.Apply(Sample(2.1)).write_setpoint.has_value());
    }
  }
}

TEST(Experiment, JointEndEndsARunningExperimentDoneAtItsNominal) {
  for (int warmup : {2, 9}) {  // while settling, and while exciting
    Driver run;
    run.Apply(Event(ExperimentEventKind::kStart));
    for (int k = 0; k < warmup; ++k) run.Apply(Sample(2.1));
    const ExperimentActions a = run.Apply(Event(ExperimentEventKind::kJointEnd));
    EXPECT_EQ(run.state.phase, ExperimentPhase::kDone);
    EXPECT_EQ(run.state.abort_reason, AbortReason::kNone);
    EXPECT_TRUE(run.state.ended_with_joint);
    EXPECT_EQ(PhaseReasonText(run.plan, run.state), "ended with its joint experiment");
    // No identification of its partial record; the nominal in the same transition.
    EXPECT_FALSE(a.start_identification);
    EXPECT_FALSE(a.record_sample);
    EXPECT_TRUE(a.phase_changed);
    EXPECT_TRUE(a.restore_nominal);
    ASSERT_TRUE(a.write_setpoint.has_value());
    EXPECT_DOUBLE_EQ(*a.write_setpoint, 0.5);
    for (int k = 0; k < 5; ++k) EXPECT_FALSE(run.Apply(Sample(2.1)).write_setpoint.has_value());
    // A new start forgets it.
    run.Apply(Event(ExperimentEventKind::kStart));
    EXPECT_FALSE(run.state.ended_with_joint);
    EXPECT_EQ(PhaseReasonText(run.plan, run.state), "settling");
  }
}

TEST(Experiment, JointEndLeavesAnExperimentThatIsNotRunningAsItIs) {
  // Idle; identifying its own record; done; aborted.
  Driver idle;
  EXPECT_FALSE(idle.Apply(Event(ExperimentEventKind::kJointEnd)).phase_changed);
  EXPECT_EQ(idle.state.phase, ExperimentPhase::kIdle);
  Driver run;
  run.Apply(Event(ExperimentEventKind::kStart));
  while (run.state.phase != ExperimentPhase::kIdentifying) run.Apply(Sample(2.1));
  const ExperimentActions a = run.Apply(Event(ExperimentEventKind::kJointEnd));
  EXPECT_FALSE(a.phase_changed);
  EXPECT_FALSE(a.write_setpoint.has_value());
  EXPECT_EQ(run.state.phase, ExperimentPhase::kIdentifying);
  run.Apply(Event(ExperimentEventKind::kIdentificationSucceeded));
  run.Apply(Event(ExperimentEventKind::kJointEnd));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kDone);
  EXPECT_FALSE(run.state.ended_with_joint);
  EXPECT_EQ(PhaseReasonText(run.plan, run.state), "done");
  Driver aborted;
  aborted.Apply(Event(ExperimentEventKind::kStart));
  aborted.Apply(Event(ExperimentEventKind::kStop));
  aborted.Apply(Event(ExperimentEventKind::kJointEnd));
  EXPECT_EQ(aborted.state.phase, ExperimentPhase::kAborted);
  EXPECT_EQ(PhaseReasonText(aborted.plan, aborted.state), "stopped by operator");
}

TEST(Experiment, ToleratesSingleInvalidSamplesButNotARunOfThem) {
  Driver run;  // max_invalid_samples = 1
  run.Apply(Event(ExperimentEventKind::kStart));
  run.Apply(Sample(0.0, false));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kSettling);
  run.Apply(Sample(2.1));
  run.Apply(Sample(0.0, false));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kSettling);
  const ExperimentActions a = run.Apply(Sample(0.0, false));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kAborted);
  EXPECT_EQ(run.state.abort_reason, AbortReason::kSensorInvalid);
  EXPECT_TRUE(a.restore_nominal);
}

TEST(Experiment, StartWhileRunningIsIgnoredAndIdleIgnoresSamples) {
  Driver run;
  EXPECT_FALSE(
      run.Apply(Sample(5.0)).write_setpoint.has_value());  // idle: out of band is no concern
  EXPECT_EQ(run.state.phase, ExperimentPhase::kIdle);
  run.Apply(Event(ExperimentEventKind::kStart));
  run.Apply(Sample(2.1));
  const ExperimentActions a = run.Apply(Event(ExperimentEventKind::kStart));
  EXPECT_FALSE(a.write_setpoint.has_value());
  EXPECT_EQ(run.state.samples_in_phase, 1);
}

TEST(Experiment, FailedIdentificationEndsAborted) {
  Driver run;
  run.plan.settle_samples = 0;
  run.plan.excite_samples = 3;
  run.Apply(Event(ExperimentEventKind::kStart));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kExciting);
  for (int k = 0; k < 3; ++k) run.Apply(Sample(2.1));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kIdentifying);
  run.Apply(Event(ExperimentEventKind::kIdentificationFailed));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kAborted);
  EXPECT_EQ(run.state.abort_reason, AbortReason::kIdentificationFailed);
}

TEST(Experiment, PlanValidationNamesTheField) {
  ExperimentPlan plan = Plan();
  plan.level_max_m = plan.level_min_m;
  try {
    plan.Validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("level_max_m"), std::string::npos);
  }
}

// Samples every 1 s; the bound 1.5 s.  A stall (SIGSTOP, an overrun, a reconnect) shows as one
// sample arriving late: the record would join two instants as if one period apart.
TEST(ExperimentSampleGap, AGapLongerThanTheBoundAbortsWhileExcitingAndRestoresNominal) {
  Driver run;
  run.plan.max_sample_gap_s = 1.5;
  run.Apply(Event(ExperimentEventKind::kStart));
  double t = 100.0;
  for (int k = 0; k < 10; ++k) run.Apply(TimedSample(2.1, t += 1.0));
  ASSERT_EQ(run.state.phase, ExperimentPhase::kExciting);
  // A late poll within the bound passes.
  run.Apply(TimedSample(2.1, t += 1.49));
  ASSERT_EQ(run.state.phase, ExperimentPhase::kExciting);
  const ExperimentActions a = run.Apply(TimedSample(2.1, t += 3.0));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kAborted);
  EXPECT_EQ(run.state.abort_reason, AbortReason::kSampleGap);
  EXPECT_DOUBLE_EQ(run.state.sample_gap_s, 3.0);
  ASSERT_TRUE(a.write_setpoint.has_value());
  EXPECT_DOUBLE_EQ(*a.write_setpoint, 0.5);
  EXPECT_TRUE(a.restore_nominal);
  EXPECT_FALSE(a.record_sample);
  EXPECT_FALSE(a.start_identification);
  EXPECT_EQ(AbortReasonText(run.plan, run.state), "sample gap of 3 s (bound 1.5 s)");
}

TEST(ExperimentSampleGap, AGapWhileSettlingAbortsToo) {
  Driver run;
  run.plan.max_sample_gap_s = 1.5;
  run.Apply(Event(ExperimentEventKind::kStart));
  run.Apply(TimedSample(2.1, 10.0));
  run.Apply(TimedSample(2.1, 11.0));
  ASSERT_EQ(run.state.phase, ExperimentPhase::kSettling);
  run.Apply(TimedSample(2.1, 12.6));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kAborted);
  EXPECT_EQ(run.state.abort_reason, AbortReason::kSampleGap);
}

TEST(ExperimentSampleGap, TimeGoingBackAborts) {
  Driver run;
  run.plan.max_sample_gap_s = 1.5;
  run.Apply(Event(ExperimentEventKind::kStart));
  run.Apply(TimedSample(2.1, 10.0));
  run.Apply(TimedSample(2.1, 9.0));
  EXPECT_EQ(run.state.abort_reason, AbortReason::kSampleGap);
  EXPECT_EQ(AbortReasonText(run.plan, run.state), "sample time went back by 1 s");
}

TEST(ExperimentSampleGap, TheLastSampleOfTheExcitationAfterAGapIsNotIdentified) {
  Driver run;
  run.plan.max_sample_gap_s = 1.5;
  run.Apply(Event(ExperimentEventKind::kStart));
  double t = 0.0;
  for (int k = 0; k < 4 + 44; ++k) run.Apply(TimedSample(2.1, t += 1.0));
  ASSERT_EQ(run.state.phase, ExperimentPhase::kExciting);
  const ExperimentActions a = run.Apply(TimedSample(2.1, t += 2.0));
  EXPECT_EQ(run.state.abort_reason, AbortReason::kSampleGap);
  EXPECT_FALSE(a.start_identification);
}

ExperimentEvent StartAt(double time_s) {
  ExperimentEvent e = Event(ExperimentEventKind::kStart);
  e.sample.time_s = time_s;
  return e;
}

TEST(ExperimentSampleGap, TheFirstSampleOfARunIsCheckedAgainstTheStartsTime) {
  Driver run;
  run.plan.max_sample_gap_s = 1.5;
  run.Apply(TimedSample(2.1, 0.0));  // idle: ignored
  run.Apply(StartAt(10.0));
  run.Apply(TimedSample(2.1, 11.0));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kSettling);
  run.Apply(Event(ExperimentEventKind::kStop));
  run.Apply(StartAt(20.0));
  run.Apply(TimedSample(2.1, 23.0));  // stalled right after the start
  EXPECT_EQ(run.state.abort_reason, AbortReason::kSampleGap);
}

TEST(ExperimentSampleGap, UntimedSamplesAndStartsAreNotChecked) {
  Driver run;
  run.plan.max_sample_gap_s = 1.5;
  run.Apply(Event(ExperimentEventKind::kStart));
  run.Apply(TimedSample(2.1, 500.0));  // no time at the start: no predecessor
  run.Apply(Sample(2.1));              // no time: not checked, not a reference
  run.Apply(TimedSample(2.1, 501.0));
  EXPECT_EQ(run.state.phase, ExperimentPhase::kSettling);
}

TEST(ExperimentSampleGap, TheBoundMustBePositive) {
  ExperimentPlan plan = Plan();
  plan.max_sample_gap_s = 0.0;
  EXPECT_THROW(plan.Validate(), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core

namespace canalid::core {
namespace {

// A step experiment: nominal + amplitude for step_hold_samples samples, then nominal for as many,
// every sample recorded, then identification with the nominal restored; the safety rules are
// those of the PRBS (a level out of band mid-step aborts to nominal).
TEST(ExperimentStep, StepsUpHoldsStepsBackAndRecordsBothHolds) {
  Driver d;
  d.plan.step_hold_samples = 5;
  d.plan.excite_samples = 10;
  d.plan.settle_samples = 2;
  d.plan.Validate();
  d.Apply(Event(ExperimentEventKind::kStart));
  EXPECT_EQ(d.Apply(Sample(2.1)).write_setpoint, std::nullopt);  // settling
  // The last settling sample writes the step's first level.
  EXPECT_EQ(d.Apply(Sample(2.1)).write_setpoint, std::optional<double>(0.54));
  std::vector<double> written;
  int recorded = 0;
  ExperimentActions a;
  for (int k = 0; k < 10; ++k) {
    a = d.Apply(Sample(2.1));
    recorded += a.record_sample;
    if (a.write_setpoint) written.push_back(*a.write_setpoint);
  }
  EXPECT_EQ(recorded, 10);
  EXPECT_TRUE(a.start_identification);
  EXPECT_TRUE(a.restore_nominal);
  // Samples 1..4 of the step up hold it; 5..9 are back at nominal; the end writes nominal.
  EXPECT_EQ(written, (std::vector<double>{0.54, 0.54, 0.54, 0.54, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5}));
  EXPECT_EQ(d.state.phase, ExperimentPhase::kIdentifying);
}

TEST(ExperimentStep, ALevelOutOfBandMidStepAbortsToNominal) {
  Driver d;
  d.plan.step_hold_samples = 20;
  d.plan.excite_samples = 40;
  d.plan.settle_samples = 0;
  d.Apply(Event(ExperimentEventKind::kStart));
  EXPECT_DOUBLE_EQ(d.state.setpoint, 0.54);
  d.Apply(Sample(2.2));
  const ExperimentActions a = d.Apply(Sample(2.35));
  EXPECT_EQ(d.state.phase, ExperimentPhase::kAborted);
  EXPECT_EQ(d.state.abort_reason, AbortReason::kLevelOutOfBand);
  EXPECT_EQ(a.write_setpoint, std::optional<double>(0.5));
  EXPECT_TRUE(a.restore_nominal);
}

TEST(ExperimentStep, TheExcitationIsTwoHolds) {
  ExperimentPlan plan = Plan();
  plan.step_hold_samples = 5;
  plan.excite_samples = 11;
  EXPECT_THROW(plan.Validate(), std::invalid_argument);
  plan.step_hold_samples = -1;
  EXPECT_THROW(plan.Validate(), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
