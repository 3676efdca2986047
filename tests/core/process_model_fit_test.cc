#include "core/linear/process_model_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace canalid::core {
namespace {

// Truth from closed-form step responses (not from the simulator under test): a step of size du
// applied at sample k0, output offset y0.
Eigen::VectorXd FoptdStepData(double k, double t_const, double tau, double ts, int n, int k0,
                              double du, double y0) {
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) {
    const double s = (i - k0) * ts - tau;
    y(i) = y0 + (s > 0.0 ? k * du * (1.0 - std::exp(-s / t_const)) : 0.0);
  }
  return y;
}

Eigen::VectorXd SoptdStepData(double k, double t1, double t2, double tau, double ts, int n, int k0,
                              double du, double y0) {
  Eigen::VectorXd y(n);
  for (int i = 0; i < n; ++i) {
    const double s = (i - k0) * ts - tau;
    y(i) = y0 +
           (s > 0.0 ? k * du * (1.0 - (t1 * std::exp(-s / t1) - t2 * std::exp(-s / t2)) / (t1 - t2))
                    : 0.0);
  }
  return y;
}

Eigen::VectorXd Step(int n, int k0, double u0, double du) {
  Eigen::VectorXd u = Eigen::VectorXd::Constant(n, u0);
  u.tail(n - k0).array() += du;
  return u;
}

TEST(FitFoptd, RecoversExactParametersFromNoiseFreeStep) {
  // The flume paper's nominal flume model, delay off the sample grid (4.1 s = 27.33 samples of 0.15
  // s).
  const double ts = 0.15;
  const int n = 2400, k0 = 40;
  const Eigen::VectorXd u = Step(n, k0, 0.20, 0.05);
  const Eigen::VectorXd y = FoptdStepData(0.372, 10.975, 4.1, ts, n, k0, 0.05, 0.31);
  const FoptdFit fit = FitFoptd(u, y, ts);
  EXPECT_NEAR(fit.model.gain, 0.372, 1e-9 * 0.372);
  EXPECT_NEAR(fit.model.time_constant_s, 10.975, 1e-9 * 10.975);
  EXPECT_NEAR(fit.model.delay_s, 4.1, 1e-9);
  EXPECT_NEAR(fit.output_offset, 0.31, 1e-10);
  EXPECT_GT(fit.metrics.fit_percent, 99.9999);
}

TEST(FitFoptd, RecoversParametersFromNoisyStepWithinTolerance) {
  // 0.15 mm noise (the flume paper's sensor) on a 18.6 mm response: K within 1 %, T within 3 %, tau
  // within 0.15 s. Tolerances are a few standard deviations of the estimator at this noise.
  const double ts = 0.15;
  const int n = 2400, k0 = 40;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.00015);
  for (const auto& [k, t, tau] :
       {std::tuple{0.372, 10.975, 4.05}, std::tuple{0.09, 2.0, 2.3}, std::tuple{0.7, 40.0, 5.6}}) {
    const Eigen::VectorXd u = Step(n, k0, 0.20, 0.05);
    Eigen::VectorXd y = FoptdStepData(k, t, tau, ts, n, k0, 0.05, 0.31);
    for (auto& v : y) v += noise(rng);
    const FoptdFit fit = FitFoptd(u, y, ts);
    EXPECT_NEAR(fit.model.gain, k, 0.01 * k);
    EXPECT_NEAR(fit.model.time_constant_s, t, 0.03 * t);
    EXPECT_NEAR(fit.model.delay_s, tau, 0.15);
  }
}

TEST(FitFoptd, FitsARichInputRecordNotOnlySteps) {
  // Pseudo-random binary input with a held clock of 25 samples; the truth is generated with an
  // independent recursion: the exact discretisation of a first order with an integer delay.
  const double ts = 1.0, k = 2.5, t = 30.0;
  const int delay = 12, n = 3000;
  std::mt19937 rng(3);
  Eigen::VectorXd u(n);
  double level = 1.0;
  for (int i = 0; i < n; ++i) {
    if (i % 25 == 0) level = (rng() & 1U) ? 1.0 : -1.0;
    u(i) = 5.0 + level;
  }
  const double a = std::exp(-ts / t);
  Eigen::VectorXd y(n);
  double x = 0.0;
  for (int i = 0; i < n; ++i) {
    y(i) = 3.0 + x;
    const double ud = i - delay >= 0 ? u(i - delay) - u(0) : 0.0;
    x = a * x + k * (1.0 - a) * ud;
  }
  const FoptdFit fit = FitFoptd(u, y, ts);
  EXPECT_NEAR(fit.model.gain, k, 1e-8 * k);
  EXPECT_NEAR(fit.model.time_constant_s, t, 1e-8 * t);
  EXPECT_NEAR(fit.model.delay_s, delay * ts, 1e-8);
}

TEST(FitSoptd, RecoversExactParametersFromNoiseFreeStep) {
  const double ts = 0.15;
  const int n = 2400, k0 = 40;
  const Eigen::VectorXd u = Step(n, k0, 0.20, 0.05);
  const Eigen::VectorXd y = SoptdStepData(0.5, 9.0, 2.5, 3.2, ts, n, k0, 0.05, 0.31);
  const SoptdFit fit = FitSoptd(u, y, ts);
  EXPECT_NEAR(fit.model.gain, 0.5, 1e-8 * 0.5);
  EXPECT_NEAR(fit.model.time_constants_s[0], 9.0, 1e-7 * 9.0);
  EXPECT_NEAR(fit.model.time_constants_s[1], 2.5, 1e-7 * 2.5);
  EXPECT_NEAR(fit.model.delay_s, 3.2, 1e-7);
}

TEST(FitSoptd, IsNeverWorseThanFoptdOnTheSameData) {
  // SOPTD contains FOPTD (T2 -> 0), so its ISE must not exceed FOPTD's.
  const double ts = 0.15;
  const int n = 1200, k0 = 20;
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.0003);
  const Eigen::VectorXd u = Step(n, k0, 0.1, 0.04);
  Eigen::VectorXd y = FoptdStepData(0.3, 6.0, 3.0, ts, n, k0, 0.04, 0.2);
  for (auto& v : y) v += noise(rng);
  const FoptdFit first = FitFoptd(u, y, ts);
  const SoptdFit second = FitSoptd(u, y, ts);
  EXPECT_LE(second.metrics.ise, first.metrics.ise * (1.0 + 1e-9));
}

TEST(FitFoptd, RejectsAnInputThatNeverMoves) {
  const Eigen::VectorXd u = Eigen::VectorXd::Constant(100, 2.0);
  const Eigen::VectorXd y = Eigen::VectorXd::LinSpaced(100, 0.0, 1.0);
  EXPECT_THROW(FitFoptd(u, y, 1.0), std::invalid_argument);
  EXPECT_THROW(FitFoptd(u.head(5), y.head(5), 1.0), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
