// The end-of-experiment process models of a reach (core/reach/process_batch.h and
// ReachSampleProcessor::IdentifyRecord): an experiment on a plant written here in closed form, a
// first-order lag with delay discretised exactly under ZOH, gives its gain, time constant and
// delay from both batch kinds; the integrator-delay fit can be left out; failures are reported.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/reach/reach_sample_processor.h"
#include "tests/core/commensurate_test_models.h"

namespace canalid::core {
namespace {

constexpr double kTs = 0.15, kGain = 0.55, kTime = 8.0;
constexpr std::size_t kDelaySamples = 20;  // 3 s

// Level = 0.05 + y, y(k+1) = a y(k) + K (1 - a) (u(k - d) - u0), a = exp(-Ts / T): the exact
// sampled FOPTD (continuous delay d Ts = 3 s) under a zero-order hold.
class FoptdFlume {
 public:
  double Step(double gate) {
    gates_.push_back(gate);
    const double a = std::exp(-kTs / kTime);
    const std::size_t n = gates_.size();
    const double delayed = n > kDelaySamples ? gates_[n - 1 - kDelaySamples] : 0.015;
    const double level = 0.05 + y_;
    y_ = a * y_ + kGain * (1.0 - a) * (delayed - 0.015);
    return level;
  }

 private:
  std::vector<double> gates_;
  double y_ = 0.0;
};

ReachSampleProcessorOptions FlumeOptions(bool batch_id) {
  ReachSampleProcessorOptions o;
  o.sample_time_s = kTs;
  o.online_id_enabled = false;
  o.online_id.max_delay_samples = 60;  // delays up to 9 s
  o.batch_id = batch_id;
  o.batch_process_models = {ProcessBatchKind::kFoptd, ProcessBatchKind::kFractionalFoptd,
                            ProcessBatchKind::kSoptd, ProcessBatchKind::kArx};
  o.batch_process.arx_na = 1;  // the flume's FOPTD sampled is a first-order ARX
  o.batch_process.arx_nb = 1;
  ExperimentPlan plan;
  plan.prbs.nominal = 0.015;
  plan.prbs.amplitude = 0.002;
  plan.prbs.clock_period_samples = 40;
  plan.prbs.order = 6;
  plan.settle_samples = 10;
  plan.excite_samples = std::int64_t{63} * 40;
  plan.level_min_m = 0.03;
  plan.level_max_m = 0.07;
  o.experiment = plan;
  return o;
}

// Runs the experiment to its end; the gate follows every setpoint written.
void RunExperiment(ReachSampleProcessor& reach) {
  FoptdFlume flume;
  double gate = 0.015;
  ReachActions a = reach.StartExperiment();
  if (a.write_setpoint) gate = *a.write_setpoint;
  for (int k = 0; k < 4000 && !a.experiment_record_complete; ++k) {
    ReachSample s;
    s.level_m = flume.Step(gate);
    s.q_in_m3s = s.q_out_m3s = 3e-4;
    s.q_in_valid = s.q_out_valid = s.level_valid = true;
    s.input = gate;
    a = reach.OnSample(s);
    if (a.write_setpoint) gate = *a.write_setpoint;
  }
  ASSERT_TRUE(a.experiment_record_complete);
}

TEST(ProcessBatch, AnExperimentGivesTheFoptdOfTheFlumeFromBothKinds) {
  ReachSampleProcessor reach(FlumeOptions(false));
  RunExperiment(reach);
  ReachActions done;
  EXPECT_FALSE(reach.IdentifyRecord(&done).has_value());  // no integrator-delay fit asked
  EXPECT_EQ(reach.experiment_state().phase, ExperimentPhase::kDone);
  const auto& results = reach.process_batch_results();
  ASSERT_EQ(results.size(), 4U);
  ASSERT_TRUE(results[0].ok()) << results[0].problem;
  ASSERT_TRUE(results[0].foptd.has_value());
  const FoptdModel& m = results[0].foptd->model;
  // Exact data of the model's own structure: the simulation-error fit finds it.
  EXPECT_NEAR(m.gain, kGain, 1e-3 * kGain);
  EXPECT_NEAR(m.time_constant_s, kTime, 1e-2 * kTime);
  EXPECT_NEAR(m.delay_s, static_cast<double>(kDelaySamples) * kTs, 0.5 * kTs);
  ASSERT_TRUE(results[1].ok()) << results[1].problem;
  const FractionalFoptdParams& f = results[1].fractional->params;
  // A first-order lag is the fractional model at alpha 1.
  EXPECT_NEAR(f.alpha, 1.0, 0.05);
  EXPECT_NEAR(f.gain, kGain, 0.02 * kGain);
  EXPECT_NEAR(f.time_constant_s, kTime, 0.15 * kTime);
  EXPECT_NEAR(f.delay_s, static_cast<double>(kDelaySamples) * kTs, 2.0 * kTs);
  // A first-order lag is the second-order one with a vanishing second time constant (FitSoptd
  // keeps T1 >= T2): the gain and T1 are the lag's, and the fit follows the record.
  ASSERT_TRUE(results[2].ok()) << results[2].problem;
  ASSERT_TRUE(results[2].soptd.has_value());
  const SoptdModel& s = results[2].soptd->model;
  EXPECT_NEAR(s.gain, kGain, 1e-2 * kGain);
  EXPECT_GE(s.time_constants_s[0], s.time_constants_s[1]);
  EXPECT_NEAR(s.time_constants_s[0], kTime, 0.15 * kTime);
  EXPECT_GT(results[2].soptd->metrics.fit_percent, 99.0);
  // The flume sampled with the gate held over each sample is exactly y(t) = a y(t-1) + K (1 - a)
  // u(t - 1 - kDelaySamples), a = e^{-Ts/T}: the arx scan finds that delay and those coefficients.
  ASSERT_TRUE(results[3].ok()) << results[3].problem;
  ASSERT_TRUE(results[3].arx.has_value());
  const ArxModel& arx = *results[3].arx;
  const double a = std::exp(-kTs / kTime);
  EXPECT_EQ(arx.orders.nk.front(), static_cast<int>(kDelaySamples) + 1);
  EXPECT_NEAR(arx.a(0), -a, 1e-9);
  EXPECT_NEAR(arx.b.front()(0), kGain * (1.0 - a), 1e-9);
  EXPECT_EQ(results[3].input_offset, 0.015);
}

// A plant that is the LPV paper's commensurate model (alpha = 0.5, Table 3's P1 OP1, its delay of
// 17 samples), simulated by SimulateCommensurate around a rest point: frac-ss finds the delay by
// its scan and the coefficients (the record at rest before the input moves, full GL memory).
TEST(ProcessBatch, FracSsFindsTheDelayAndCoefficientsOfACommensuratePlant) {
  const CommensurateModel m = testdata::SeedOneHalf();
  const int samples = 700;
  // A random binary input held 7 samples, at rest (0) at the first sample.
  Eigen::VectorXd du(samples);
  std::mt19937 rng(11);
  double level = 0.1;
  for (int k = 0; k < samples; ++k) {
    if (k % 7 == 1) level = (rng() & 1U) != 0U ? 0.1 : -0.1;
    du(k) = k == 0 ? 0.0 : level;
  }
  const Eigen::VectorXd dy = SimulateCommensurate(m, du);
  const Eigen::VectorXd u = du.array() + 1.5;
  const Eigen::VectorXd y = dy.array() + 2.0;
  ProcessBatchOptions options;
  options.max_delay_s = 30 * kTs;
  options.frac_ss_q = 2;
  options.frac_ss_memory_samples = samples;
  const ProcessBatchResult r = FitProcessBatch(ProcessBatchKind::kFracSs, u, y, kTs, options);
  ASSERT_TRUE(r.ok()) << r.problem;
  ASSERT_TRUE(r.commensurate.has_value());
  EXPECT_EQ(r.commensurate->model.delay_samples, 17);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(r.commensurate->model.a(i), m.a(i), 1e-5 * (1e-3 + std::abs(m.a(i)))) << i;
  }
  EXPECT_NEAR(r.commensurate->model.c(0), m.c(0), 1e-3 * std::abs(m.c(0)));
  EXPECT_EQ(r.commensurate->input_offset, 1.5);
  EXPECT_EQ(r.commensurate->output_offset, 2.0);
  EXPECT_EQ(r.memory_samples, samples);
  EXPECT_EQ(ProcessBatchKindName(ProcessBatchKind::kFracSs), "frac-ss");

  options.max_delay_s = 10 * kTs;  // the true delay outside the scan: a worse model
  const ProcessBatchResult short_scan =
      FitProcessBatch(ProcessBatchKind::kFracSs, u, y, kTs, options);
  ASSERT_TRUE(short_scan.commensurate.has_value());
  EXPECT_LE(short_scan.commensurate->model.delay_samples, 10);
  EXPECT_LT(short_scan.commensurate->metrics.fit_percent, r.commensurate->metrics.fit_percent);
}

// max_delay_s = 0 (a reach whose delays stop at 0) keeps only delay 0: the flume's 3 s delay is
// out of bounds, and arx has no delay to scan; a negative one is each fit's own default.
TEST(ProcessBatch, MaxDelayZeroKeepsOnlyDelayZero) {
  FoptdFlume flume;
  Eigen::VectorXd u(800), y(800);
  for (Eigen::Index k = 0; k < u.size(); ++k) {
    u(k) = k < 100 ? 0.015 : 0.017;
    y(k) = flume.Step(u(k));
  }
  ProcessBatchOptions zero;
  zero.max_delay_s = 0.0;
  const ProcessBatchResult foptd = FitProcessBatch(ProcessBatchKind::kFoptd, u, y, kTs, zero);
  ASSERT_TRUE(foptd.fitted());
  EXPECT_NE(foptd.problem.find("is outside [0, 0"), std::string::npos) << foptd.problem;
  const ProcessBatchResult arx = FitProcessBatch(ProcessBatchKind::kArx, u, y, kTs, zero);
  EXPECT_FALSE(arx.fitted());
  EXPECT_NE(arx.problem.find("too short for delays of 1 samples"), std::string::npos)
      << arx.problem;
  const ProcessBatchResult free = FitProcessBatch(ProcessBatchKind::kFoptd, u, y, kTs, {});
  ASSERT_TRUE(free.ok()) << free.problem;
  EXPECT_NEAR(free.foptd->model.delay_s, static_cast<double>(kDelaySamples) * kTs, 0.5 * kTs);
}

// A reach with no batch kind only moves its actuator (the partner of a joint experiment): its
// experiment ends done, with no model and no problem to report.
TEST(ProcessBatch, WithoutAnyModelTheExperimentEndsDoneWithNoModel) {
  ReachSampleProcessorOptions o = FlumeOptions(false);
  o.batch_process_models.clear();
  ASSERT_FALSE(o.batch_id);
  ASSERT_FALSE(o.batch_idz.has_value());
  ReachSampleProcessor reach(o);
  RunExperiment(reach);
  ReachActions done;
  EXPECT_FALSE(reach.IdentifyRecord(&done).has_value());
  EXPECT_EQ(reach.experiment_state().phase, ExperimentPhase::kDone);
  EXPECT_TRUE(reach.identification_problem().empty()) << reach.identification_problem();
  EXPECT_TRUE(reach.process_batch_results().empty());
}

TEST(ProcessBatch, AFitThatCannotRunIsAProblemNotAThrow) {
  const Eigen::VectorXd still = Eigen::VectorXd::Constant(100, 0.015);
  const Eigen::VectorXd level = Eigen::VectorXd::Constant(100, 0.05);
  for (const ProcessBatchKind kind : kProcessBatchKinds) {
    const ProcessBatchResult r = FitProcessBatch(kind, still, level, kTs, ProcessBatchOptions{9.0});
    EXPECT_FALSE(r.ok()) << ProcessBatchKindName(kind);
    EXPECT_FALSE(r.foptd.has_value() || r.fractional.has_value() || r.commensurate.has_value());
    if (kind == ProcessBatchKind::kFracSs) {
      EXPECT_NE(r.problem.find("never moves"), std::string::npos) << r.problem;
    }
  }
  EXPECT_EQ(ProcessBatchKindName(ProcessBatchKind::kFractionalFoptd), "frac-foptd");
}

}  // namespace
}  // namespace canalid::core
