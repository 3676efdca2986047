#include "core/fractional/fractional_simulator.h"
#include "tests/support/frac_step_reference.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/fractional/fractional_foptd.h"

namespace canalid::core {
namespace {

// The accuracy asked of both simulators: 0.5 % of K at the sample times.
constexpr double kRelativeTolerance = 5e-3;

FractionalSimOptions Method(FractionalSimMethod method) {
  FractionalSimOptions options;
  options.method = method;
  return options;
}

// Largest |simulated - exact| over a unit step applied at sample step_index (truth from the
// Mittag-Leffler closed form, not from a simulator).
double WorstStepError(const FractionalFoptdParams& p, double ts, int n, int step_index,
                      FractionalSimMethod method) {
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  u.tail(n - step_index).setOnes();
  const Eigen::VectorXd y = SimulateFractionalFoptd(p, u, ts, Method(method));
  double worst = 0.0;
  // Every sample through the rise, then every 7th (the closed form costs ~1e3 flops).
  for (int k = 0; k < n; k += (k < step_index + 300 ? 1 : 7)) {
    const double truth = FractionalFoptdStepResponse(p, (k - step_index) * ts);
    worst = std::max(worst, std::abs(y(k) - truth));
  }
  return worst;
}

using ReferenceRow = testing::FracStepReferenceRow;
std::vector<ReferenceRow> ReadReference() { return testing::ReadFracStepReference(); }

TEST(FractionalSimulatorTest, OustaloupMatchesTheReferenceCsv) {
  const std::vector<ReferenceRow> rows = ReadReference();
  ASSERT_EQ(rows.size(), 16u);
  const double ts = 0.25;  // every reference time is a whole number of samples
  for (const ReferenceRow& row : rows) {
    const FractionalFoptdParams p{row.gain, row.time_constant_s, row.alpha, 0.0};
    const int k = static_cast<int>(std::lround(row.t_s / ts));
    const Eigen::VectorXd y = SimulateFractionalFoptd(p, Eigen::VectorXd::Ones(k + 1), ts,
                                                      Method(FractionalSimMethod::kOustaloup));
    EXPECT_NEAR(y(k), row.response, kRelativeTolerance * row.gain)
        << "alpha " << row.alpha << " t " << row.t_s;
  }
}

TEST(FractionalSimulatorTest, GrunwaldLetnikovMatchesTheReferenceCsv) {
  // GL1 with full memory is O(N^2): the rows up to t = 100 s (Oustaloup covers t = 1000 s).
  const double ts = 0.25;
  for (const ReferenceRow& row : ReadReference()) {
    if (row.t_s > 100.0) continue;
    const FractionalFoptdParams p{row.gain, row.time_constant_s, row.alpha, 0.0};
    const int k = static_cast<int>(std::lround(row.t_s / ts));
    const Eigen::VectorXd y = SimulateFractionalFoptd(
        p, Eigen::VectorXd::Ones(k + 1), ts, Method(FractionalSimMethod::kGrunwaldLetnikov));
    EXPECT_NEAR(y(k), row.response, kRelativeTolerance * row.gain)
        << "alpha " << row.alpha << " t " << row.t_s;
  }
}

TEST(FractionalSimulatorTest, OustaloupMatchesMittagLefflerAcrossOrders) {
  // The flume paper's sampling (Ts = 0.15 s, 360 s) over and beyond its ranges, with sub-sample
  // delays.
  for (double alpha : {0.5, 0.6, 0.8, 0.95, 1.1, 1.25, 1.5, 1.8}) {
    for (double t_c : {1.17, 10.975, 48.0}) {
      for (double tau : {0.0, 2.25, 4.07}) {
        const FractionalFoptdParams p{0.372, t_c, alpha, tau};
        EXPECT_LT(WorstStepError(p, 0.15, 2400, 20, FractionalSimMethod::kOustaloup),
                  kRelativeTolerance * p.gain)
            << "alpha " << alpha << " T " << t_c << " tau " << tau;
      }
    }
  }
}

TEST(FractionalSimulatorTest, GrunwaldLetnikovMatchesMittagLefflerAcrossOrders) {
  // 60 s records keep the O(N^2) cost low; the GL1 error peaks early in the response.
  for (double alpha : {0.6, 0.8, 1.25, 1.6}) {
    for (double t_c : {1.17, 10.975}) {
      const FractionalFoptdParams p{0.775, t_c, alpha, 3.37};
      EXPECT_LT(WorstStepError(p, 0.15, 400, 10, FractionalSimMethod::kGrunwaldLetnikov),
                kRelativeTolerance * p.gain)
          << "alpha " << alpha << " T " << t_c;
    }
  }
}

TEST(FractionalSimulatorTest, OrderOneIsTheExactFirstOrderWithSubSampleDelay) {
  // K (1 - exp(-(t - tau)/T)) to rounding for both methods (exact ZOH, not an approximation).
  const FractionalFoptdParams p{0.372, 10.975, 1.0, 4.05};
  for (FractionalSimMethod method :
       {FractionalSimMethod::kOustaloup, FractionalSimMethod::kGrunwaldLetnikov}) {
    const int n = 2400, step_index = 7;
    Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
    u.tail(n - step_index).setConstant(2.5);
    const Eigen::VectorXd y = SimulateFractionalFoptd(p, u, 0.15, Method(method));
    for (int k = 0; k < n; ++k) {
      const double t = (k - step_index) * 0.15 - p.delay_s;
      const double truth = t > 0 ? 2.5 * p.gain * (1.0 - std::exp(-t / p.time_constant_s)) : 0.0;
      ASSERT_NEAR(y(k), truth, 1e-12) << "k " << k;
    }
  }
}

TEST(FractionalSimulatorTest, ArbitraryInputsFollowSuperposition) {
  // Up, down and a negative excursion: the truth is the sum of shifted closed-form steps.
  const FractionalFoptdParams p{0.5, 6.0, 0.7, 2.6};
  const double ts = 0.15;
  const int n = 1200;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  u.segment(30, 300).setConstant(10.0);
  u.segment(330, 400).setConstant(-4.0);
  const Eigen::VectorXd y = SimulateFractionalFoptd(p, u, ts);
  double worst = 0.0;
  for (int k = 0; k < n; ++k) {
    double truth = 0.0;
    double previous = 0.0;
    for (int j = 0; j < k; ++j) {
      if (u(j) != previous)
        truth += (u(j) - previous) * FractionalFoptdStepResponse(p, (k - j) * ts);
      previous = u(j);
    }
    worst = std::max(worst, std::abs(y(k) - truth));
  }
  EXPECT_LT(worst, kRelativeTolerance * p.gain * 14.0);  // 14 = the largest input swing
}

TEST(FractionalSimulatorTest, StreamingEqualsBatch) {
  const FractionalFoptdParams p{0.3, 4.0, 0.85, 1.0};
  Eigen::VectorXd u(300);
  for (int k = 0; k < 300; ++k) u(k) = std::sin(0.05 * k) + (k > 100 ? 1.0 : 0.0);
  const Eigen::VectorXd batch = SimulateFractionalFoptd(p, u, 0.15);
  OustaloupFoptdSimulator sim(p, 0.15, DefaultOustaloupOptions(p, 0.15, 300 * 0.15));
  for (int k = 0; k < 300; ++k) {
    EXPECT_DOUBLE_EQ(sim.output(), batch(k));
    sim.Advance(u(k));
  }
  sim.Reset();
  EXPECT_EQ(sim.output(), 0.0);
}

TEST(FractionalSimulatorTest, ShortMemoryFollowsTheTailBound) {
  // alpha = 1.5: the GL tail decays like L^-1.5, so a 1 % static-gain tolerance needs a short
  // memory; the settled value must then sit within that tolerance of K (exact value: K).
  const FractionalFoptdParams p{1.0, 2.0, 1.5, 0.0};
  FractionalSimOptions options = Method(FractionalSimMethod::kGrunwaldLetnikov);
  options.gl_static_gain_tolerance = 1e-2;
  const int samples = 2000;
  const int memory = GlMemoryLength(p, 0.15, samples, options);
  const int full = samples * DefaultGlSubsteps(p, 0.15);
  EXPECT_LT(memory, full / 4);
  const Eigen::VectorXd y =
      SimulateFractionalFoptd(p, Eigen::VectorXd::Ones(samples), 0.15, options);
  EXPECT_NEAR(y(samples - 1), 1.0, 1e-2);
  // alpha = 0.6 cannot reach 1e-3 within the record: the memory is capped at the full record.
  options.gl_static_gain_tolerance = 1e-3;
  EXPECT_EQ(GlMemoryLength({1.0, 10.0, 0.6, 0.0}, 0.15, 100, options),
            100 * DefaultGlSubsteps({1.0, 10.0, 0.6, 0.0}, 0.15));
}

TEST(FractionalSimulatorTest, RejectsBadArguments) {
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(10);
  EXPECT_THROW(SimulateFractionalFoptd({1.0, 1.0, 2.0, 0.0}, u, 0.1), std::invalid_argument);
  EXPECT_THROW(SimulateFractionalFoptd({1.0, -1.0, 0.5, 0.0}, u, 0.1), std::invalid_argument);
  EXPECT_THROW(SimulateFractionalFoptd({1.0, 1.0, 0.5, -0.1}, u, 0.1), std::invalid_argument);
  EXPECT_THROW(SimulateFractionalFoptd({1.0, 1.0, 0.5, 0.0}, u, 0.0), std::invalid_argument);
  EXPECT_THROW(GlFoptdSimulator({1.0, 1.0, 0.5, 0.0}, 0.1, 0, 10), std::invalid_argument);
}

// Regression: a model JSON's "oustaloup": {"sections_per_decade": 1000} built a ~8000-state
// simulator (the CLI ran for minutes) and 1e9 overflowed the section count to 1 (a wrong
// simulation with exit 0).  The band of `canalid identify` on asce2-pool2-step.csv.
TEST(FractionalSimulatorTest, RejectsAnOustaloupDensityBeyondTheBound) {
  const FractionalFoptdParams p{5.987, 123660.0, 0.9427, 303.3};
  for (const double density : {1000.0, 1e9}) {
    const OustaloupOptions band{3.966679888932964e-08, 5.0, density};
    EXPECT_THROW(OustaloupFoptdSimulator(p, 10.0, band), std::invalid_argument) << density;
  }
  EXPECT_NO_THROW(OustaloupFoptdSimulator(p, 10.0, {3.966679888932964e-08, 5.0, 20.0}));
}

}  // namespace
}  // namespace canalid::core
