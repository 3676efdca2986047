#include "core/fractional/fractional_foptd_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "core/fractional/fractional_foptd.h"

namespace canalid::core {
namespace {

constexpr double kTs = 0.15;  // the flume paper: Ts = 0.15 s, 360 s per experiment
constexpr int kSamples = 2400;
constexpr double kNoiseMm = 0.15;

struct Experiment {
  FractionalFoptdParams truth;
  Eigen::VectorXd u, y, noise;
};

// A gate step from u_i to u_f (mm, the flume paper's grid 10..50 mm) at sample step_index, level in
// mm from the Mittag-Leffler closed form (not from the simulator the fit uses).
Experiment GateStep(const FractionalFoptdParams& p, double u_i, double u_f, int step_index,
                    double noise_mm, std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, noise_mm);
  Experiment e{p, Eigen::VectorXd(kSamples), Eigen::VectorXd(kSamples), Eigen::VectorXd(kSamples)};
  for (int k = 0; k < kSamples; ++k) {
    e.u(k) = k < step_index ? u_i : u_f;
    e.noise(k) = noise_mm > 0 ? noise(rng) : 0.0;
    e.y(k) =
        60.0 + (u_f - u_i) * FractionalFoptdStepResponse(p, (k - step_index) * kTs) + e.noise(k);
  }
  return e;
}

// Parameters drawn inside the flume paper's ranges (K 0.086..0.775, T 1.17..48 s log-uniform, tau
// 2.25..5.7 s, alpha 0.6..1.25) and a gate step on the flume paper's 5 mm grid.
Experiment DrawExperiment(std::mt19937& rng, double min_change_mm, double noise_mm) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> gate(0, 8);
  std::uniform_int_distribution<int> start(1, 100);
  for (;;) {
    FractionalFoptdParams p;
    p.gain = 0.086 + unit(rng) * (0.775 - 0.086);
    p.time_constant_s = 1.17 * std::pow(48.0 / 1.17, unit(rng));
    p.delay_s = 2.25 + unit(rng) * (5.7 - 2.25);
    p.alpha = 0.6 + unit(rng) * 0.65;
    const double u_i = 10.0 + 5.0 * gate(rng);
    const double u_f = 10.0 + 5.0 * gate(rng);
    if (std::abs(p.gain * (u_f - u_i)) < min_change_mm) continue;
    return GateStep(p, u_i, u_f, start(rng), noise_mm, rng);
  }
}

bool WithinSpec(const FractionalFoptdParams& fit, const FractionalFoptdParams& truth) {
  return std::abs(fit.alpha - truth.alpha) < 0.05 &&
         std::abs(fit.time_constant_s / truth.time_constant_s - 1.0) < 0.10 &&
         std::abs(fit.gain / truth.gain - 1.0) < 0.03 &&
         std::abs(fit.delay_s - truth.delay_s) < 0.4;
}

TEST(FractionalFoptdFitTest, RecoversNoiseFreeGateStepsTightly) {
  // Without noise only the Oustaloup model error (~0.3 % of K at 2 sections/decade) biases the
  // fit: measured worst 0.2 % in K, 0.3 % in T, 0.001 in alpha, 0.01 s in tau.
  std::mt19937 rng(7);
  for (int c = 0; c < 10; ++c) {
    const Experiment e = DrawExperiment(rng, 0.5, 0.0);
    const FractionalFoptdFitResult r = FitFractionalFoptd(e.u, e.y, kTs);
    EXPECT_NEAR(r.params.alpha, e.truth.alpha, 0.01) << "case " << c;
    EXPECT_NEAR(r.params.time_constant_s / e.truth.time_constant_s, 1.0, 0.02) << "case " << c;
    EXPECT_NEAR(r.params.gain / e.truth.gain, 1.0, 0.01) << "case " << c;
    EXPECT_NEAR(r.params.delay_s, e.truth.delay_s, 0.05) << "case " << c;
    EXPECT_NEAR(r.output_offset, 60.0, 1e-3) << "case " << c;
    EXPECT_GT(r.metrics.fit_percent, 99.0);
  }
}

TEST(FractionalFoptdFitTest, MeetsTheAccuracySpecOnNoisyGateSteps) {
  // 0.15 mm noise on level changes of at least 3 mm (20 sigma).  The spec (alpha 0.05, T 10 %,
  // K 3 %, tau 0.4 s) must hold on at least 90 % of the cases (measured: 95 of 100 on other
  // seeds).  Every case, inside the spec or not, must reach a simulation error no larger than
  // the noise itself (the error of the true model): a miss is then the noise's doing, not a
  // local minimum of the fit.
  std::mt19937 rng(2024);
  const int cases = 30;
  int within = 0;
  for (int c = 0; c < cases; ++c) {
    const Experiment e = DrawExperiment(rng, 3.0, kNoiseMm);
    const FractionalFoptdFitResult r = FitFractionalFoptd(e.u, e.y, kTs);
    const double fit_sse = (r.simulated - e.y).squaredNorm();
    // 0.1 % slack: the fit's own model error (Oustaloup) is far below the noise.
    EXPECT_LE(fit_sse, e.noise.squaredNorm() * 1.001) << "case " << c;
    const bool ok = WithinSpec(r.params, e.truth);
    within += ok;
    if (!ok) {
      std::printf(
          "outside spec (noise-limited): K %.3f/%.3f T %.2f/%.2f alpha %.3f/%.3f tau %.2f/%.2f\n",
          r.params.gain, e.truth.gain, r.params.time_constant_s, e.truth.time_constant_s,
          r.params.alpha, e.truth.alpha, r.params.delay_s, e.truth.delay_s);
    }
  }
  EXPECT_GE(within, 27) << within << " of " << cases << " within spec";
}

TEST(FractionalFoptdFitTest, FitsAnyInputRecord) {
  // A PRBS-like record (random switching between two gate openings every 5..40 s) with noise;
  // truth by superposition of closed-form steps.
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> hold(33, 266);
  const FractionalFoptdParams truth{0.372, 10.975, 0.8, 4.05};
  Eigen::VectorXd u(kSamples);
  double level = 20.0;
  for (int k = 0, next = 20; k < kSamples; ++k) {
    if (k == next) {
      level = level == 20.0 ? 35.0 : 20.0;
      next += hold(rng);
    }
    u(k) = level;
  }
  std::normal_distribution<double> noise(0.0, kNoiseMm);
  Eigen::VectorXd y(kSamples);
  for (int k = 0; k < kSamples; ++k) {
    double response = 0.0;
    for (int j = 1; j < k; ++j) {
      if (u(j) != u(j - 1))
        response += (u(j) - u(j - 1)) * FractionalFoptdStepResponse(truth, (k - j) * kTs);
    }
    y(k) = 50.0 + response + noise(rng);
  }
  const FractionalFoptdFitResult r = FitFractionalFoptd(u, y, kTs);
  EXPECT_TRUE(WithinSpec(r.params, truth)) << r.params.gain << " " << r.params.time_constant_s
                                           << " " << r.params.alpha << " " << r.params.delay_s;
}

TEST(FractionalFoptdFitTest, IntegerFirstOrderDataGivesOrderOne) {
  std::mt19937 rng(3);
  const Experiment e = GateStep({0.5, 8.0, 1.0, 3.0}, 20.0, 40.0, 10, kNoiseMm, rng);
  const FractionalFoptdFitResult r = FitFractionalFoptd(e.u, e.y, kTs);
  EXPECT_NEAR(r.params.alpha, 1.0, 0.03);
  EXPECT_NEAR(r.params.time_constant_s, 8.0, 0.4);
}

TEST(FractionalFoptdFitTest, StagedEstimateWithoutRefinementIsClose) {
  // The flume paper's staged procedure alone (no joint LM): a coarse but sane starting point.
  std::mt19937 rng(5);
  const Experiment e = GateStep({0.4, 10.0, 0.8, 4.0}, 20.0, 40.0, 10, 0.0, rng);
  FractionalFoptdFitOptions options;
  options.refine = false;
  const FractionalFoptdFitResult r = FitFractionalFoptd(e.u, e.y, kTs, options);
  EXPECT_NEAR(r.params.gain, 0.4, 0.02);   // final value at 360 s is 97 % settled
  EXPECT_NEAR(r.params.alpha, 0.8, 0.21);  // alpha grid step 0.2
  EXPECT_NEAR(r.params.delay_s, 4.0, 1.0);
}

TEST(FractionalFoptdFitTest, RejectsBadArguments) {
  const Eigen::VectorXd flat = Eigen::VectorXd::Constant(100, 3.0);
  const Eigen::VectorXd y = Eigen::VectorXd::Zero(100);
  EXPECT_THROW(FitFractionalFoptd(flat, y, kTs), std::invalid_argument);
  EXPECT_THROW(FitFractionalFoptd(flat, Eigen::VectorXd::Zero(99), kTs), std::invalid_argument);
  Eigen::VectorXd step = flat;
  step.tail(50).setConstant(4.0);
  EXPECT_THROW(FitFractionalFoptd(step, y, 0.0), std::invalid_argument);
  FractionalFoptdFitOptions bad;
  bad.alpha_max = 2.5;
  EXPECT_THROW(FitFractionalFoptd(step, y, kTs, bad), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
