#include "core/experiment/experiment_design.h"

#include <gtest/gtest.h>

#include <string>

namespace canalid::core {
namespace {

ExperimentDesignRequest Request(double flow_m3s, double delay_s, double ts_s) {
  ExperimentDesignRequest r;
  r.nominal_flow_m3s = flow_m3s;
  r.expected_delay_s = delay_s;
  r.sample_time_s = ts_s;
  return r;
}

bool Mentions(const ExperimentDesign& d, const std::string& text) {
  for (const std::string& line : d.explanation) {
    if (line.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(ExperimentDesign, HalfDelayClockAndSmallestCoveringOrder) {
  // 682 s delay, 60 s sampling: 341 s / 60 s = 5.68 -> 6 samples (360 s).  5 x 682 = 3410 s:
  // order 3 gives 7 x 360 = 2520 s (too short), order 4 gives 15 x 360 = 5400 s.
  const ExperimentDesign d = DesignPrbsExperiment(Request(2.0, 682.0, 60.0));
  EXPECT_DOUBLE_EQ(d.amplitude_m3s, 0.15);  // default 7.5 %
  EXPECT_EQ(d.clock_period_samples, 6);
  EXPECT_DOUBLE_EQ(d.clock_period_s, 360.0);
  EXPECT_EQ(d.order, 4);
  EXPECT_EQ(d.num_periods, 1);
  EXPECT_EQ(d.num_samples, 90);
  EXPECT_DOUBLE_EQ(d.duration_s, 5400.0);
  EXPECT_TRUE(
      Mentions(d, "clock period 341 s = half the 682 s delay, rounded to 6 samples of 60 s"))
      << d.explanation[1];
  EXPECT_TRUE(Mentions(d, "order 4"));
}

TEST(ExperimentDesign, ArizonaReachTwo) {
  // Arizona reach 2: delay guess 90 min.  Clock 45 min; 5 x 90 = 450 min needs order 4
  // (15 x 45 = 675 min; order 3 gives 315 min).  The study ran 540 min (12 clocks).
  const ExperimentDesign d = DesignPrbsExperiment(Request(1.0, 5400.0, 60.0));
  EXPECT_EQ(d.clock_period_samples, 45);
  EXPECT_EQ(d.order, 4);
  EXPECT_DOUBLE_EQ(d.duration_s, 675.0 * 60.0);
  EXPECT_GE(d.duration_s, 5.0 * 5400.0);
}

TEST(ExperimentDesign, DelayShorterThanTwoSamplesGivesOneSampleClock) {
  // Half of 50 s is 0.42 samples of 60 s: rounds to 0, clamped to 1 sample, and said so.
  const ExperimentDesign d = DesignPrbsExperiment(Request(1.0, 50.0, 60.0));
  EXPECT_EQ(d.clock_period_samples, 1);
  EXPECT_TRUE(Mentions(d, "shorter than half a sample"));
  // 5 x 50 = 250 s: order 3 (7 x 60 = 420 s) is the smallest covering (order 2: 180 s).
  EXPECT_EQ(d.order, 3);
  EXPECT_EQ(d.num_samples, 7);
  // 90 s: 0.75 samples rounds to 1 normally; 450 s needs order 4 (900 s; order 3 is 420 s).
  const ExperimentDesign e = DesignPrbsExperiment(Request(1.0, 90.0, 60.0));
  EXPECT_EQ(e.clock_period_samples, 1);
  EXPECT_EQ(e.order, 4);
}

TEST(ExperimentDesign, RepeatsPeriodsWhenTheLargestOrderIsTooShort) {
  ExperimentDesignRequest r = Request(1.0, 6000.0, 1.0);
  r.max_order = 3;
  // Clock 3000 samples; one order-3 period is 21000 s < 30000 s required: 2 periods.
  const ExperimentDesign d = DesignPrbsExperiment(r);
  EXPECT_EQ(d.clock_period_samples, 3000);
  EXPECT_EQ(d.order, 3);
  EXPECT_EQ(d.num_periods, 2);
  EXPECT_EQ(d.num_samples, 42000);
  EXPECT_TRUE(Mentions(d, "repeated 2 times"));
}

TEST(ExperimentDesign, LongerDurationFactorRaisesTheOrder) {
  ExperimentDesignRequest r = Request(1.0, 682.0, 60.0);
  r.duration_factor = 10.0;  // 6820 s > 5400 s of order 4: order 5 (31 x 360 = 11160 s)
  EXPECT_EQ(DesignPrbsExperiment(r).order, 5);
  r.amplitude_percent = 5.0;
  EXPECT_DOUBLE_EQ(DesignPrbsExperiment(r).amplitude_m3s, 0.05);
  r.amplitude_percent = 10.0;
  EXPECT_DOUBLE_EQ(DesignPrbsExperiment(r).amplitude_m3s, 0.1);
}

TEST(ExperimentDesign, RejectsAmplitudeOutsideFiveToTenPercent) {
  ExperimentDesignRequest r = Request(1.0, 600.0, 60.0);
  for (double bad : {4.99, 10.01, 0.0, -7.5}) {
    r.amplitude_percent = bad;
    try {
      DesignPrbsExperiment(r);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("amplitude_percent"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("[5.000000, 10.000000]"), std::string::npos) << e.what();
    }
  }
}

TEST(ExperimentDesign, RejectsNonPositiveInputs) {
  EXPECT_THROW(DesignPrbsExperiment(Request(0.0, 600.0, 60.0)), std::invalid_argument);
  EXPECT_THROW(DesignPrbsExperiment(Request(1.0, 0.0, 60.0)), std::invalid_argument);
  EXPECT_THROW(DesignPrbsExperiment(Request(1.0, 600.0, -1.0)), std::invalid_argument);
  ExperimentDesignRequest r = Request(1.0, 600.0, 60.0);
  r.max_order = 32;
  EXPECT_THROW(DesignPrbsExperiment(r), std::invalid_argument);
  r.max_order = 16;
  r.duration_factor = 4.0;
  EXPECT_THROW(DesignPrbsExperiment(r), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
