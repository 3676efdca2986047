#include "core/linear/integrator_wave_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>
#include <stdexcept>

namespace canalid::core {
namespace {

// Closed-form unit-step response of k/(s (S s^2 + M s + 1)) by partial fractions:
//   k [t - M + sum_i (M S p_i + M^2 - S) / (2 S p_i + M) e^{p_i t}],  p_i roots of S s^2 + M s + 1.
double StepResponse(const IntegratorWaveModel& m, double t) {
  t -= m.delay_s;
  if (t <= 0.0) return 0.0;
  const double s = m.s_coeff_s2, mm = m.m_coeff_s;
  const std::complex<double> root = std::sqrt(std::complex<double>(mm * mm - 4.0 * s, 0.0));
  double sum = 0.0;
  for (const std::complex<double> p : {(-mm + root) / (2.0 * s), (-mm - root) / (2.0 * s)}) {
    sum += ((mm * s * p + mm * mm - s) / (2.0 * s * p + mm) * std::exp(p * t)).real();
  }
  return m.gain * (t - mm + sum);
}

Eigen::VectorXd StepSuperposition(const IntegratorWaveModel& m, const Eigen::VectorXd& u,
                                  double ts) {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(u.size());
  for (Eigen::Index j = 0; j < u.size(); ++j) {
    const double jump = u(j) - (j > 0 ? u(j - 1) : 0.0);
    if (jump == 0.0) continue;
    for (Eigen::Index k = j + 1; k < u.size(); ++k)
      y(k) += jump * StepResponse(m, static_cast<double>(k - j) * ts);
  }
  return y;
}

Eigen::VectorXd Prbs(int steps, unsigned seed) {
  std::mt19937 rng(seed);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(steps);
  double level = 1.0;
  for (int k = 10; k < steps; ++k) {
    if (k % 30 == 0) level = (rng() % 2) ? 1.0 : -1.0;
    u(k) = level;
  }
  return u;
}

const IntegratorWaveModel kUnderDamped{0.02, 25.0, 4.0, 6.3};  // zeta = 0.4, tau not on the grid

TEST(IntegratorWaveModelTest, ZohSimulationIsExactForHeldInputs) {
  for (const IntegratorWaveModel& m : {kUnderDamped, IntegratorWaveModel{0.05, 4.0, 5.0, 2.0}}) {
    const Eigen::VectorXd u = Prbs(400, 1);
    const Eigen::VectorXd y = SimulateIntegratorWave(m, u, 0.5);
    const Eigen::VectorXd truth = StepSuperposition(m, u, 0.5);
    EXPECT_LT((y - truth).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + truth.cwiseAbs().maxCoeff()));
  }
}

TEST(IntegratorWaveModelTest, FitRecoversNoiseFreeAndNoisyModels) {
  const Eigen::VectorXd u = Prbs(1200, 2);
  const Eigen::VectorXd clean = StepSuperposition(kUnderDamped, u, 0.5);
  IntegratorWaveFit r = FitIntegratorWave(u, clean.array() + 10.0, 0.5);
  // Noise free: only the LM tolerances remain.
  EXPECT_NEAR(r.model.gain, kUnderDamped.gain, 1e-5 * kUnderDamped.gain);
  EXPECT_NEAR(r.model.s_coeff_s2, kUnderDamped.s_coeff_s2, 1e-3 * kUnderDamped.s_coeff_s2);
  EXPECT_NEAR(r.model.m_coeff_s, kUnderDamped.m_coeff_s, 1e-3 * kUnderDamped.m_coeff_s);
  EXPECT_NEAR(r.model.delay_s, kUnderDamped.delay_s, 1e-3);
  EXPECT_NEAR(r.output_offset, 10.0, 1e-6);

  // Noise at 2 % of the output's range: parameters within 5 % (delay within 0.25 s).
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.02 * (clean.maxCoeff() - clean.minCoeff()));
  Eigen::VectorXd y = clean;
  for (Eigen::Index k = 0; k < y.size(); ++k) y(k) += noise(rng);
  r = FitIntegratorWave(u, y, 0.5);
  EXPECT_NEAR(r.model.gain / kUnderDamped.gain, 1.0, 0.05);
  EXPECT_NEAR(r.model.s_coeff_s2 / kUnderDamped.s_coeff_s2, 1.0, 0.05);
  EXPECT_NEAR(r.model.m_coeff_s / kUnderDamped.m_coeff_s, 1.0, 0.05);
  EXPECT_NEAR(r.model.delay_s, kUnderDamped.delay_s, 0.25);
}

TEST(IntegratorWaveModelTest, RejectsBadArguments) {
  EXPECT_THROW(SimulateIntegratorWave({1.0, 0.0, 1.0, 0.0}, Eigen::VectorXd::Ones(5), 0.5),
               std::invalid_argument);
  EXPECT_THROW(SimulateIntegratorWave({1.0, 1.0, 1.0, 0.0}, Eigen::VectorXd::Ones(5), 0.0),
               std::invalid_argument);
  EXPECT_THROW(FitIntegratorWave(Eigen::VectorXd::Ones(50), Eigen::VectorXd::Ones(50), 0.5),
               std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
