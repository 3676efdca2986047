#include "core/online/online_commensurate.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

#include "core/fractional/commensurate_state_space.h"
#include "tests/core/commensurate_test_models.h"

namespace canalid::core {
namespace {

using testdata::IntegerSecondOrder;
using testdata::SeedOneHalf;

// A +-1 random binary input held `hold` samples (deterministic).
Eigen::VectorXd Prbs(int samples, int hold, unsigned seed) {
  std::mt19937 rng(seed);
  Eigen::VectorXd u(samples);
  double level = 1.0;
  for (int k = 0; k < samples; ++k) {
    if (k % hold == 0) level = (rng() & 1U) != 0U ? 1.0 : -1.0;
    u(k) = level;
  }
  return u;
}

OnlineCommensurateOptions Options(const CommensurateModel& m, int memory) {
  OnlineCommensurateOptions o;
  o.q = m.q;
  o.delay_samples = m.delay_samples;
  o.memory_samples = memory;
  o.rls.method = RlsMethod::kExponential;
  o.rls.forgetting = 1.0;
  o.rls.initial_covariance = 1e10;
  return o;
}

OnlineCommensurate Estimate(const CommensurateModel& m, const Eigen::VectorXd& u,
                            const Eigen::VectorXd& y, int memory) {
  OnlineCommensurate estimator(Options(m, memory));
  for (Eigen::Index k = 0; k < u.size(); ++k) estimator.Update(u(k), y(k));
  return estimator;
}

// Noise-free data from the state-space simulation (SimulateCommensurate, full memory): the
// input-output recursion the estimator regresses on is exact, so the true a and c come back.
TEST(OnlineCommensurate, RecoversNoiseFreeModelsFromTheStateSpaceSimulation) {
  for (const CommensurateModel& m : {SeedOneHalf(), IntegerSecondOrder()}) {
    const Eigen::VectorXd u = Prbs(800, 3, 3);
    const Eigen::VectorXd y = SimulateCommensurate(m, u);
    const OnlineCommensurate e = Estimate(m, u, y, 800);
    for (int i = 1; i <= m.order(); ++i) {
      EXPECT_NEAR(e.a(i), m.a(i - 1), 1e-6 * (1e-3 + std::abs(m.a(i - 1)))) << "q " << m.q;
    }
    for (int i = 1; i < m.order(); ++i) {
      EXPECT_NEAR(e.c(i), m.c(i - 1), 1e-4 * (1.0 + std::abs(m.c(i - 1)))) << "q " << m.q;
    }
  }
}

// With output noise (equation error is then biased), the online estimate is the batch least
// squares of FitCommensurate's first stage (a QR solve of the whole record), up to the prior.
TEST(OnlineCommensurate, EqualsTheBatchLeastSquaresOnANoisyRecord) {
  const CommensurateModel m = IntegerSecondOrder();
  const Eigen::VectorXd u = Prbs(600, 4, 4);
  Eigen::VectorXd y = SimulateCommensurate(m, u);
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.02);
  for (Eigen::Index k = 0; k < y.size(); ++k) y(k) += noise(rng);
  // The batch fit takes deviations from the first sample; start the record at rest (0, 0).
  Eigen::VectorXd u0(u.size() + 1), y0(y.size() + 1);
  u0 << 0.0, u;
  y0 << 0.0, y;
  CommensurateFitOptions batch_options;
  batch_options.refine = false;
  const CommensurateFitResult batch =
      FitCommensurate(u0, y0, m.q, m.delay_samples, 1.0, batch_options);
  const OnlineCommensurate e = Estimate(m, u0, y0, 1000);
  for (int i = 1; i <= m.order(); ++i) {
    EXPECT_NEAR(e.a(i), batch.initial.a(i - 1), 1e-7) << i;
  }
  EXPECT_NEAR(e.c(1), batch.initial.c(0), 1e-6);
  EXPECT_GT(e.a_std(1), 0.0);
  std::array<double, 1> c_std{};
  e.CStandardDeviations(c_std);
  EXPECT_GT(c_std[0], 0.0);
  EXPECT_LT(c_std[0], 0.1);
}

// A lost level reading: skipped, and its place in the GL history taken by the model's prediction,
// so the estimate stays on the truth.
TEST(OnlineCommensurate, ABadOutputIsSkippedAndPredicted) {
  const CommensurateModel m = IntegerSecondOrder();
  const Eigen::VectorXd u = Prbs(600, 3, 5);
  Eigen::VectorXd y = SimulateCommensurate(m, u);
  y(400) = std::numeric_limits<double>::quiet_NaN();
  y(401) = 1e300;
  const OnlineCommensurate e = Estimate(m, u, y, 600);
  EXPECT_EQ(e.bad_outputs(), 2);
  EXPECT_NEAR(e.a(1), m.a(0), 1e-6);
  EXPECT_NEAR(e.a(2), m.a(1), 1e-6);
  EXPECT_NEAR(e.c(1), m.c(0), 1e-5);
}

// A short GL memory changes the recursion (the state-space truncation is another model), so it
// is an approximation whose error grows as L shrinks: still close at L = 100 on this record.
TEST(OnlineCommensurate, ShortMemoryApproximatesTheFullOne) {
  const CommensurateModel m = IntegerSecondOrder();
  const Eigen::VectorXd u = Prbs(800, 3, 6);
  const Eigen::VectorXd y = SimulateCommensurate(m, u);
  // q = 1: every difference has integer order, whose GL weights end after n terms: exact.
  const OnlineCommensurate e = Estimate(m, u, y, 3);
  EXPECT_NEAR(e.a(1), m.a(0), 1e-6);
  EXPECT_NEAR(e.c(1), m.c(0), 1e-5);
  const CommensurateModel half = SeedOneHalf();
  const Eigen::VectorXd yh = SimulateCommensurate(half, u);
  const OnlineCommensurate full = Estimate(half, u, yh, 800);
  const OnlineCommensurate short_memory = Estimate(half, u, yh, 100);
  EXPECT_NEAR(short_memory.a(1), full.a(1), 0.05 * std::abs(full.a(1)));
  EXPECT_NE(short_memory.a(1), full.a(1));
}

TEST(OnlineCommensurate, OptionsOutOfRangeAreNamed) {
  OnlineCommensurateOptions o;
  o.q = 5;
  try {
    OnlineCommensurate e(o);
    FAIL() << "q = 5 accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("OnlineCommensurateOptions.q"), std::string::npos)
        << error.what();
  }
  o.q = 2;
  o.memory_samples = 0;
  EXPECT_THROW(OnlineCommensurate{o}, std::invalid_argument);
  o.memory_samples = 10;
  o.delay_samples = -1;
  EXPECT_THROW(OnlineCommensurate{o}, std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
