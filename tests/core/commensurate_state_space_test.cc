#include "core/fractional/commensurate_state_space.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "tests/core/commensurate_test_models.h"

namespace canalid::core {
namespace {

// ln |Gamma(x)|: lgamma_r, since lgamma writes the global signgam (not thread-safe).
double LogGamma(double x) {
  int sign = 0;
  return ::lgamma_r(x, &sign);
}

using testdata::IntegerSecondOrder;
using testdata::SeedOneHalf;
using testdata::SeedOneQuarter;

// Independent implementation: dense companion matrices and weights from the Gamma function,
// w_j = Gamma(j - alpha) / (Gamma(-alpha) Gamma(j + 1)).
Eigen::VectorXd NaiveSimulation(const CommensurateModel& m, const Eigen::VectorXd& u) {
  const int n = m.order();
  const double alpha = m.alpha();
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i + 1 < n; ++i) a(i, i + 1) = 1.0;
  for (int j = 0; j < n; ++j) a(n - 1, j) = -m.a(n - 1 - j);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  b(n - 1) = m.a(n - 1);
  Eigen::RowVectorXd c(n);
  c << 1.0, m.c.transpose();
  const Eigen::Index steps = u.size();
  Eigen::VectorXd w(steps + 2);
  for (Eigen::Index j = 0; j < w.size(); ++j) {
    if (alpha == 1.0) {
      w(j) = j == 0 ? 1.0 : (j == 1 ? -1.0 : 0.0);
    } else {
      w(j) = std::exp(LogGamma(static_cast<double>(j) - alpha) -
                      LogGamma(static_cast<double>(j) + 1.0)) /
             std::tgamma(-alpha);
    }
  }
  std::vector<Eigen::VectorXd> x(static_cast<size_t>(steps + 1), Eigen::VectorXd::Zero(n));
  Eigen::VectorXd y(steps);
  for (Eigen::Index k = 0; k < steps; ++k) {
    y(k) = c * x[static_cast<size_t>(k)];
    const Eigen::Index ki = k - m.delay_samples;
    Eigen::VectorXd next = a * x[static_cast<size_t>(k)] + b * (ki >= 0 ? u(ki) : 0.0);
    for (Eigen::Index j = 1; j <= k + 1; ++j) next -= w(j) * x[static_cast<size_t>(k + 1 - j)];
    x[static_cast<size_t>(k + 1)] = next;
  }
  return y;
}

// The LPV paper excites with a PRBS around the operating point; at rest for the first 30 samples.
Eigen::VectorXd Prbs(int steps, unsigned seed) {
  std::mt19937 rng(seed);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(steps);
  double level = 1.0;
  for (int k = 30; k < steps; ++k) {
    if (k % 20 == 0) level = (rng() % 2) ? 1.0 : -1.0;
    u(k) = level;
  }
  return u;
}

TEST(CommensurateStateSpaceTest, SimulationMatchesAnIndependentImplementation) {
  const Eigen::VectorXd u = Prbs(600, 1);
  for (const CommensurateModel& m : {SeedOneHalf(), SeedOneQuarter(), IntegerSecondOrder()}) {
    const Eigen::VectorXd y = SimulateCommensurate(m, u);
    const Eigen::VectorXd truth = NaiveSimulation(m, u);
    ASSERT_TRUE(y.allFinite());
    // Relative to the output scale: the two weight formulas differ by rounding only.
    EXPECT_LT((y - truth).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + truth.cwiseAbs().maxCoeff()))
        << "q " << m.q;
  }
}

TEST(CommensurateStateSpaceTest, UnitStaticGain) {
  // Delta^alpha of a constant tends to zero, so x1 -> u and y -> u (slowly: the GL tail decays
  // like k^-alpha).
  CommensurateModel m = IntegerSecondOrder();
  m.delay_samples = 0;
  const Eigen::VectorXd y = SimulateCommensurate(m, Eigen::VectorXd::Ones(400));
  EXPECT_NEAR(y(399), 1.0, 1e-6);
}

TEST(CommensurateStateSpaceTest, ShortMemoryLongerThanTheRecordIsExact) {
  const Eigen::VectorXd u = Prbs(300, 2);
  const Eigen::VectorXd full = SimulateCommensurate(SeedOneHalf(), u);
  const Eigen::VectorXd longer = SimulateCommensurate(SeedOneHalf(), u, 500);
  EXPECT_LT((full - longer).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::VectorXd shorter = SimulateCommensurate(SeedOneHalf(), u, 50);
  EXPECT_GT((full - shorter).cwiseAbs().maxCoeff(), 1e-6);  // truncation does change the model
}

TEST(CommensurateStateSpaceTest, LeastSquaresRecoversNoiseFreeModelsExactly) {
  // The GL-expanded recursion is exact for noise-free data from rest: only rounding remains.
  for (const CommensurateModel& m : {SeedOneHalf(), SeedOneQuarter(), IntegerSecondOrder()}) {
    const Eigen::VectorXd u = Prbs(800, 3);
    const Eigen::VectorXd y = NaiveSimulation(m, u);
    CommensurateFitOptions options;
    options.refine = false;
    const CommensurateFitResult r = FitCommensurate(u, y, m.q, m.delay_samples, 0.5, options);
    for (int i = 0; i < m.order(); ++i) {
      EXPECT_NEAR(r.model.a(i), m.a(i), 1e-6 * (1e-3 + std::abs(m.a(i)))) << "q " << m.q;
    }
    for (int i = 0; i + 1 < m.order(); ++i) {
      EXPECT_NEAR(r.model.c(i), m.c(i), 1e-5 * (1.0 + std::abs(m.c(i)))) << "q " << m.q;
    }
    EXPECT_GT(r.metrics.fit_percent, 99.99);
  }
}

TEST(CommensurateStateSpaceTest, LevenbergMarquardtImprovesANoisyFit) {
  // 5 % output noise (relative to the output's standard deviation): equation-error least
  // squares is biased; the simulation-error refinement must (a) not fit worse than the true
  // model fits the noisy data, and (b) reproduce the noise-free output within 5 % of its range.
  for (const CommensurateModel& m : {IntegerSecondOrder(), SeedOneHalf()}) {
    const Eigen::VectorXd u = Prbs(600, 4);
    const Eigen::VectorXd clean = NaiveSimulation(m, u);
    const double scale = std::sqrt((clean.array() - clean.mean()).square().mean());
    std::mt19937 rng(9);
    std::normal_distribution<double> noise(0.0, 0.05 * scale);
    Eigen::VectorXd y = clean;
    for (Eigen::Index k = 0; k < y.size(); ++k) y(k) += noise(rng);
    const CommensurateFitResult r = FitCommensurate(u, y, m.q, m.delay_samples, 0.5);
    EXPECT_LE((r.simulated - y).squaredNorm(), (clean - y).squaredNorm() * 1.001);
    const Eigen::VectorXd fitted_clean = SimulateCommensurate(r.model, u);
    const double range = clean.maxCoeff() - clean.minCoeff();
    EXPECT_LT((fitted_clean - clean).cwiseAbs().maxCoeff(), 0.05 * range);
    const Eigen::VectorXd ls_clean = SimulateCommensurate(r.initial, u);
    EXPECT_LE((fitted_clean - clean).squaredNorm(), (ls_clean - clean).squaredNorm());
  }
}

TEST(CommensurateStateSpaceTest, DelayScanFindsTheDelay) {
  for (const CommensurateModel& m : {SeedOneHalf(), IntegerSecondOrder()}) {
    const Eigen::VectorXd u = Prbs(500, 6);
    const Eigen::VectorXd y = NaiveSimulation(m, u);
    CommensurateFitOptions options;
    options.refine = false;
    const CommensurateFitResult r = FitCommensurateScanDelay(u, y, m.q, 25, 0.5, options);
    EXPECT_EQ(r.model.delay_samples, m.delay_samples) << "q " << m.q;
    EXPECT_GT(r.metrics.fit_percent, 99.99);
  }
}

TEST(CommensurateStateSpaceTest, RejectsBadArguments) {
  CommensurateModel m = SeedOneHalf();
  m.c.resize(2);
  EXPECT_THROW(SimulateCommensurate(m, Eigen::VectorXd::Ones(10)), std::invalid_argument);
  EXPECT_THROW(FitCommensurate(Eigen::VectorXd::Ones(10), Eigen::VectorXd::Ones(10), 2, 0, 0.5),
               std::invalid_argument);
  EXPECT_THROW(FitCommensurate(Prbs(200, 1), Eigen::VectorXd::Ones(200), 0, 0, 0.5),
               std::invalid_argument);
  // An input that never moves: nothing to fit, said by both fits (the LPV locals and the daemon's
  // batch frac-ss go through them).
  const Eigen::VectorXd still = Eigen::VectorXd::Constant(200, 0.3);
  for (const bool scan : {false, true}) {
    try {
      if (scan) {
        FitCommensurateScanDelay(still, Prbs(200, 1), 2, 5, 0.5);
      } else {
        FitCommensurate(still, Prbs(200, 1), 2, 0, 0.5);
      }
      ADD_FAILURE() << "no throw, scan " << scan;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("the input never moves from its first value"),
                std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace canalid::core
