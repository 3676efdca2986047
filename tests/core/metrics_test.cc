#include "core/numerics/metrics.h"

#include <gtest/gtest.h>

#include <cmath>

namespace canalid::core {
namespace {

TEST(Metrics, MatchHandComputedValues) {
  Eigen::VectorXd y(4), y_sim(4);
  y << 0.0, 1.0, 2.0, 3.0;
  y_sim << 0.0, 1.0, 2.0, 5.0;  // one error of 2
  const FitMetrics m = ComputeMetrics(y, y_sim, 0.5);
  EXPECT_DOUBLE_EQ(m.rmse, 1.0);                                            // sqrt(4/4)
  EXPECT_DOUBLE_EQ(m.mae, 0.5);                                             // 2/4
  EXPECT_DOUBLE_EQ(m.ise, 2.0);                                             // 4 * 0.5
  EXPECT_NEAR(m.fit_percent, 100.0 * (1.0 - 2.0 / std::sqrt(5.0)), 1e-12);  // ||y-mean|| = sqrt(5)
  // dy: 5 % window of 4 samples is 1 sample: |3 - 0| = 3 = range, t_f = 2 s.
  EXPECT_NEAR(m.norm_error, std::sqrt(2.0 / 2.0) / 3.0, 1e-12);
}

TEST(Metrics, PerfectSimulationScoresHundredPercent) {
  Eigen::VectorXd y = Eigen::VectorXd::LinSpaced(10, 1.0, 2.0);
  const FitMetrics m = ComputeMetrics(y, y, 1.0);
  EXPECT_DOUBLE_EQ(m.fit_percent, 100.0);
  EXPECT_DOUBLE_EQ(m.norm_error, 0.0);
}

TEST(Metrics, RejectsMismatchedSizes) {
  EXPECT_THROW(ComputeMetrics(Eigen::VectorXd::Zero(3), Eigen::VectorXd::Zero(4), 1.0),
               std::invalid_argument);
  EXPECT_THROW(ComputeMetrics(Eigen::VectorXd::Zero(3), Eigen::VectorXd::Zero(3), 0.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
