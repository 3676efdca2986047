#include "core/experiment.h"

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
    state = std::move(t.state);
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
  for (int k = 0; k < 45; ++k) EXPECT_DOUBLE_EQ(written[k], expected(k)) << k;
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

}  // namespace
}  // namespace canalid::core
