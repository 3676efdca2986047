#include "core/linear/process_models.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>

namespace canalid::core {
namespace {

// Closed forms of unit-step responses (step applied at t = 0, held) are the truth here.
double FoptdStep(double k, double t_const, double tau, double t) {
  return t < tau ? 0.0 : k * (1.0 - std::exp(-(t - tau) / t_const));
}

double SoptdStep(double k, double t1, double t2, double tau, double t) {
  if (t < tau) return 0.0;
  const double s = t - tau;
  if (std::abs(t1 - t2) < 1e-12) return k * (1.0 - (1.0 + s / t1) * std::exp(-s / t1));
  return k * (1.0 - (t1 * std::exp(-s / t1) - t2 * std::exp(-s / t2)) / (t1 - t2));
}

TEST(ProcessModels, FoptdStepMatchesClosedFormWithSubSampleDelay) {
  const double ts = 0.15;
  const FoptdModel model{0.372, 10.975,
                         4.05};  // the flume paper's nominal flume model; 4.05 = 27 Ts
  const FoptdModel shifted{0.372, 10.975, 4.1};  // 27.33 Ts: exercises the fractional part
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(2400);
  for (const auto& m : {model, shifted}) {
    const Eigen::VectorXd y = Simulate(m, u, ts);
    for (Eigen::Index k = 0; k < u.size(); k += 7) {
      EXPECT_NEAR(
          y(k), FoptdStep(m.gain, m.time_constant_s, m.delay_s, static_cast<double>(k) * ts), 1e-12)
          << "k=" << k;
    }
  }
}

TEST(ProcessModels, SoptdStepMatchesClosedFormIncludingEqualTimeConstants) {
  const double ts = 0.5;
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(400);
  for (const SoptdModel m : {SoptdModel{2.0, {12.0, 3.0}, 7.3}, SoptdModel{2.0, {5.0, 5.0}, 1.0}}) {
    const Eigen::VectorXd y = Simulate(m, u, ts);
    for (Eigen::Index k = 0; k < u.size(); k += 3) {
      EXPECT_NEAR(y(k),
                  SoptdStep(m.gain, m.time_constants_s[0], m.time_constants_s[1], m.delay_s,
                            static_cast<double>(k) * ts),
                  1e-12)
          << "k=" << k;
    }
  }
}

TEST(ProcessModels, IsLinearInTheInput) {
  // A pulse train is the difference of shifted steps, so the response must be too.
  const double ts = 1.0;
  const FoptdModel m{1.5, 8.0, 2.6};
  Eigen::VectorXd step = Eigen::VectorXd::Ones(100);
  Eigen::VectorXd pulse = Eigen::VectorXd::Zero(100);
  pulse.segment(10, 20).setOnes();
  const Eigen::VectorXd y = Simulate(m, pulse, ts);
  const Eigen::VectorXd s = Simulate(m, step, ts);
  for (Eigen::Index k = 0; k < 100; ++k) {
    const double expected = (k >= 10 ? s(k - 10) : 0.0) - (k >= 30 ? s(k - 30) : 0.0);
    EXPECT_NEAR(y(k), expected, 1e-12);
  }
}

TEST(ProcessModels, RejectsNonPhysicalParameters) {
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(5);
  EXPECT_THROW(Simulate(FoptdModel{1.0, 0.0, 0.0}, u, 1.0), std::invalid_argument);
  EXPECT_THROW(Simulate(FoptdModel{1.0, 1.0, -1.0}, u, 1.0), std::invalid_argument);
  EXPECT_THROW(Simulate(SoptdModel{1.0, {1.0, -2.0}, 0.0}, u, 1.0), std::invalid_argument);
  EXPECT_THROW(Simulate(FoptdModel{1.0, 1.0, 0.0}, u, 0.0), std::invalid_argument);
}

// Regression: the delay in samples was cast to int unchecked, so a delay of 1e12 s at Ts = 10 s
// (1e11 samples) or 150 s at Ts = 6e-8 s (2.5e9 samples) wrapped to a negative count and the
// simulation read far outside u (SIGSEGV in `canalid simulate`).
TEST(ProcessModels, RejectsDelaysBeyondTheSampleBoundNamingIt) {
  const Eigen::VectorXd u = Eigen::VectorXd::Ones(5);
  for (const auto& [delay_s, ts] : {std::pair{1e12, 10.0}, std::pair{150.0, 6e-8}}) {
    try {
      Simulate(FoptdModel{1.0, 100.0, delay_s}, u, ts);
      ADD_FAILURE() << "foptd delay " << delay_s << " s at Ts " << ts << " s was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("samples must be in [0, 1e7]"), std::string::npos)
          << e.what();
    }
    EXPECT_THROW(Simulate(SoptdModel{1.0, {100.0, 50.0}, delay_s}, u, ts), std::invalid_argument);
  }
  // The bound itself is accepted: the output stays at rest over a record shorter than the delay.
  const Eigen::VectorXd y = Simulate(FoptdModel{1.0, 100.0, 1e7}, u, 1.0);
  EXPECT_EQ(y, Eigen::VectorXd::Zero(5));
}

}  // namespace
}  // namespace canalid::core
