#include "core/reach/reach_sample_processor.h"

#include <gtest/gtest.h>

#include <cmath>

namespace canalid::core {
namespace {

// A pool obeying the discrete ID model (A = 34113 m2, nk = 11 at Ts = 60 s) whose inflow follows
// the actuator: q_in = 20 * setpoint (an undershot gate at fixed heads, linearised).
class IdPool {
 public:
  double Step(double setpoint) {
    inflow_history_.push_back(20.0 * setpoint);
    const std::size_t n = inflow_history_.size();
    const double delayed = n > 11 ? inflow_history_[n - 1 - 11] : 10.0;
    level_ += 60.0 / 34113.0 * (delayed - 10.0);
    return level_;
  }
  double inflow() const { return inflow_history_.back(); }

 private:
  std::vector<double> inflow_history_;
  double level_ = 2.1;
};

ReachSampleProcessorOptions Options() {
  ReachSampleProcessorOptions o;
  o.sample_time_s = 60.0;
  o.online_id.min_delay_samples = 0;
  o.online_id.max_delay_samples = 30;
  ExperimentPlan plan;
  plan.prbs.nominal = 0.5;
  plan.prbs.amplitude = 0.0375;  // 7.5 %
  plan.prbs.clock_period_samples = 6;
  plan.prbs.order = 7;
  plan.settle_samples = 5;
  plan.excite_samples = 600;
  plan.level_min_m = 1.5;
  plan.level_max_m = 2.7;
  o.experiment = plan;
  o.batch.fit.max_nk = 30;
  return o;
}

// Starts the plan's experiment and feeds the pool until its record is complete (at most 700
// samples), the setpoint following the pipeline's writes; returns the last actions.
ReachActions RunExperiment(ReachSampleProcessor& pipeline, IdPool& pool, double* setpoint) {
  ReachActions a = pipeline.StartExperiment();
  if (a.write_setpoint) *setpoint = *a.write_setpoint;
  for (int k = 0; k < 700 && !a.experiment_record_complete; ++k) {
    const double level = pool.Step(*setpoint);
    a = pipeline.OnSample({pool.inflow(), 10.0, level, true, true, true, true});
    if (a.write_setpoint) *setpoint = *a.write_setpoint;
  }
  return a;
}

TEST(ReachSampleProcessor, AnExperimentOnAnIdPoolIdentifiesItsDelayAndArea) {
  ReachSampleProcessor pipeline(Options());
  IdPool pool;
  double setpoint = 0.5;
  const ReachActions a = RunExperiment(pipeline, pool, &setpoint);
  ASSERT_TRUE(a.experiment_record_complete);
  EXPECT_TRUE(a.restore_nominal);
  EXPECT_DOUBLE_EQ(setpoint, 0.5);
  EXPECT_EQ(pipeline.recorded_samples(), 600);
  ReachActions done;
  const auto result = pipeline.IdentifyRecord(&done);
  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(pipeline.experiment_state().phase, ExperimentPhase::kDone);
  EXPECT_EQ(result->fit.model.nk, 11);
  EXPECT_NEAR(result->fit.model.area_m2(), 34113.0, 1e-6 * 34113.0);
  // The online bank saw the same samples (plus the settling ones).
  const IntegratorDelaySnapshot online = pipeline.online_id()->Snapshot();
  EXPECT_TRUE(online.valid);
  EXPECT_EQ(online.delay_samples, 11);
  EXPECT_NEAR(online.area_m2, 34113.0, 0.01 * 34113.0);
}

// batch_models = ["idz"] alone: the IDZ fit of the same record decides the experiment.
TEST(ReachSampleProcessor, AnIdzOnlyReachIdentifiesTheIdzModelAtTheEnd) {
  ReachSampleProcessorOptions options = Options();
  options.batch_id = false;
  options.batch_idz = IdzIdentificationOptions{};
  options.batch_idz->fit.max_nk = 30;
  ReachSampleProcessor pipeline(options);
  IdPool pool;
  double setpoint = 0.5;
  ASSERT_TRUE(RunExperiment(pipeline, pool, &setpoint).experiment_record_complete);
  ReachActions done;
  EXPECT_FALSE(pipeline.IdentifyRecord(&done).has_value());  // no id model asked
  ASSERT_TRUE(pipeline.idz_result().has_value()) << pipeline.idz_problem();
  EXPECT_EQ(pipeline.idz_problem(), "");
  EXPECT_EQ(pipeline.experiment_state().phase, ExperimentPhase::kDone);
  const IdzFit& fit = pipeline.idz_result()->fit;
  EXPECT_EQ(fit.nk, 11);
  EXPECT_NEAR(fit.area_m2, 34113.0, 1e-6 * 34113.0);
  EXPECT_EQ(fit.p22_source, OutflowGainSource::kNone);  // the outflow was held
}

TEST(ReachSampleProcessor, ALevelOutOfBandAbortsAndRestoresNominalOnTheSameSample) {
  ReachSampleProcessor pipeline(Options());
  pipeline.StartExperiment();
  for (int k = 0; k < 10; ++k) pipeline.OnSample({10.0, 10.0, 2.1, true, true, true, true});
  const ReachActions a = pipeline.OnSample({10.0, 10.0, 2.75, true, true, true, true});
  EXPECT_EQ(pipeline.experiment_state().phase, ExperimentPhase::kAborted);
  EXPECT_TRUE(a.restore_nominal);
  ASSERT_TRUE(a.write_setpoint.has_value());
  EXPECT_DOUBLE_EQ(*a.write_setpoint, 0.5);
}

TEST(ReachSampleProcessor, ALostLinkAbortsWithoutASample) {
  ReachSampleProcessor pipeline(Options());
  pipeline.StartExperiment();
  for (int k = 0; k < 8; ++k) pipeline.OnSample({10.0, 10.0, 2.1, true, true, true, true});
  const ReachActions a = pipeline.OnLinkLost();
  EXPECT_EQ(pipeline.experiment_state().phase, ExperimentPhase::kAborted);
  EXPECT_EQ(pipeline.experiment_state().abort_reason, AbortReason::kLinkLost);
  EXPECT_TRUE(a.restore_nominal);
  EXPECT_EQ(pipeline.samples(), 8);
  // Idle: nothing to do.
  EXPECT_FALSE(ReachSampleProcessor(Options()).OnLinkLost().write_setpoint.has_value());
}

TEST(ReachSampleProcessor, InvalidSamplesNeitherCorruptTheEstimateNorCrash) {
  ReachSampleProcessor pipeline(Options());
  const double nan = std::nan("");
  pipeline.OnSample({nan, 10.0, 2.1, false, true, true, true});
  pipeline.OnSample({10.0, nan, nan, true, false, false, true});
  EXPECT_EQ(pipeline.samples(), 2);
  EXPECT_EQ(pipeline.experiment_state().phase, ExperimentPhase::kIdle);
}

TEST(ReachSampleProcessor, ASampleGapAbortsTheExperimentAndItsRecordIsNeverIdentified) {
  ReachSampleProcessorOptions options = Options();
  options.experiment->max_sample_gap_s = 1.5;  // polled every 1 s (wall)
  ReachSampleProcessor pipeline(options);
  IdPool pool;
  ReachActions a = pipeline.StartExperiment();
  double setpoint = *a.write_setpoint;
  double t = 1000.0;
  auto sample = [&](double time_s) {
    const double level = pool.Step(setpoint);
    ReachSample s{pool.inflow(), 10.0, level, true, true, true, true};
    s.time_s = time_s;
    a = pipeline.OnSample(s);
    if (a.write_setpoint) setpoint = *a.write_setpoint;
  };
  for (int k = 0; k < 100; ++k) sample(t += 1.0);
  ASSERT_EQ(pipeline.experiment_state().phase, ExperimentPhase::kExciting);
  const Eigen::Index recorded = pipeline.recorded_samples();
  sample(t += 3.0);  // the daemon stopped for 3 s
  EXPECT_EQ(pipeline.experiment_state().phase, ExperimentPhase::kAborted);
  EXPECT_EQ(pipeline.experiment_state().abort_reason, AbortReason::kSampleGap);
  EXPECT_TRUE(a.restore_nominal);
  EXPECT_DOUBLE_EQ(setpoint, 0.5);
  EXPECT_FALSE(a.experiment_record_complete);
  EXPECT_EQ(pipeline.recorded_samples(), recorded);  // the late sample is not recorded
  for (int k = 0; k < 600; ++k) {
    sample(t += 1.0);
    EXPECT_FALSE(a.experiment_record_complete);
  }
}

// The pool's delay is 11 samples; a bank (and batch scan) of 0..11 puts it on the bank's edge,
// where the true delay may lie outside: the model is returned for the operator to see, but the
// experiment ends "identification failed" and says why.
TEST(ReachSampleProcessor, ABatchModelAtTheEdgeOfTheBankIsNotTheReachsModel) {
  ReachSampleProcessorOptions options = Options();
  options.online_id.max_delay_samples = 11;
  options.batch.fit.max_nk = 11;
  ReachSampleProcessor pipeline(options);
  IdPool pool;
  ReachActions a = pipeline.StartExperiment();
  double setpoint = *a.write_setpoint;
  for (int k = 0; k < 700 && !a.experiment_record_complete; ++k) {
    const double level = pool.Step(setpoint);
    a = pipeline.OnSample({pool.inflow(), 10.0, level, true, true, true, true});
    if (a.write_setpoint) setpoint = *a.write_setpoint;
  }
  ASSERT_TRUE(a.experiment_record_complete);
  ReachActions done;
  const auto result = pipeline.IdentifyRecord(&done);
  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->fit.model.nk, 11);
  EXPECT_EQ(pipeline.experiment_state().phase, ExperimentPhase::kAborted);
  EXPECT_EQ(pipeline.experiment_state().abort_reason, AbortReason::kIdentificationFailed);
  EXPECT_EQ(pipeline.identification_problem(),
            "delay 11 samples is at the edge of the bank [0, 11]: the true delay may lie outside "
            "it");
}

}  // namespace
}  // namespace canalid::core
