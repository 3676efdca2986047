#include "core/linear/arx.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace canalid::core {
namespace {

// A stable 2-input system written out in MATLAB's convention, independently of the library:
//   y(t) - 1.5 y(t-1) + 0.7 y(t-2) = 1.0 u1(t-1) + 0.5 u1(t-2)
//                                   - 0.3 u2(t-3) + 0.2 u2(t-4) + 0.1 u2(t-5) + e(t)
// (na = 2, nb = [2 3], nk = [1 3]; poles 0.75 +- 0.37i, radius 0.84).
struct Truth {
  std::vector<double> a = {-1.5, 0.7};
  std::vector<double> b1 = {1.0, 0.5};
  std::vector<double> b2 = {-0.3, 0.2, 0.1};
};

ArxOrders TruthOrders() {
  ArxOrders o;
  o.na = 2;
  o.nb = {2, 3};
  o.nk = {1, 3};
  return o;
}

struct Data {
  Eigen::VectorXd y;
  Eigen::MatrixXd u;
};

Data Generate(int n, double noise_std, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Data d{Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Zero(n, 2)};
  for (int t = 0; t < n; ++t) {
    d.u(t, 0) = normal(rng);
    d.u(t, 1) = normal(rng) > 0.0 ? 1.0 : -1.0;  // a random binary input
  }
  const Truth truth;
  auto y = [&](int t) { return t >= 0 ? d.y(t) : 0.0; };
  auto u = [&](int t, int i) { return t >= 0 ? d.u(t, i) : 0.0; };
  for (int t = 0; t < n; ++t) {
    d.y(t) = -truth.a[0] * y(t - 1) - truth.a[1] * y(t - 2) + truth.b1[0] * u(t - 1, 0) +
             truth.b1[1] * u(t - 2, 0) + truth.b2[0] * u(t - 3, 1) + truth.b2[1] * u(t - 4, 1) +
             truth.b2[2] * u(t - 5, 1) + noise_std * normal(rng);
  }
  return d;
}

Eigen::VectorXd TruthVector() {
  Eigen::VectorXd theta(7);
  theta << -1.5, 0.7, 1.0, 0.5, -0.3, 0.2, 0.1;
  return theta;
}

TEST(Arx, RecoversExactCoefficientsFromNoiseFreeTwoInputData) {
  const Data d = Generate(500, 0.0, 1);
  const ArxModel m = FitArx(d.y, d.u, TruthOrders());
  ASSERT_EQ(m.num_parameters(), 7);
  EXPECT_LT((m.parameters - TruthVector()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(m.a(0), -1.5, 1e-9);
  EXPECT_NEAR(m.a(1), 0.7, 1e-9);
  ASSERT_EQ(m.b.size(), 2U);
  EXPECT_NEAR(m.b[0](0), 1.0, 1e-9);
  EXPECT_NEAR(m.b[1](2), 0.1, 1e-9);
  // First sample with every regressor: max(na, nb + nk - 1) = max(2, 2, 5) = 5.
  EXPECT_EQ(m.first_sample, 5);
  EXPECT_EQ(m.num_samples, 495);
  EXPECT_LT(m.loss, 1e-20);
}

TEST(Arx, DirectFeedthroughWithNkZero) {
  // y(t) + 0.5 y(t-1) = 2 u(t): nk = 0 puts u(t) in the regressor.
  Eigen::VectorXd u = Eigen::VectorXd::LinSpaced(50, 0.0, 1.0).array().sin();
  u(7) = 3.0;
  Eigen::VectorXd y(50);
  for (int t = 0; t < 50; ++t) y(t) = 2.0 * u(t) - 0.5 * (t > 0 ? y(t - 1) : 0.0);
  ArxOrders o;
  o.na = 1;
  o.nb = {1};
  o.nk = {0};
  const ArxModel m = FitArx(y, u, o);
  EXPECT_NEAR(m.a(0), 0.5, 1e-10);
  EXPECT_NEAR(m.b[0](0), 2.0, 1e-10);
  EXPECT_EQ(m.first_sample, 1);
}

TEST(Arx, RecoversCoefficientsFromNoisyDataWithinTheirStandardDeviations) {
  // Equation-error noise (the ARX assumption) with sigma = 0.1: LS is unbiased, so each estimate
  // must lie within 4 reported standard deviations of the truth (fails with probability ~1e-4
  // per parameter for a correct std), and V estimates sigma^2 = 0.01 to a few %.
  const Data d = Generate(5000, 0.1, 7);
  const ArxModel m = FitArx(d.y, d.u, TruthOrders());
  const Eigen::VectorXd truth = TruthVector();
  for (int i = 0; i < 7; ++i) {
    EXPECT_LT(std::abs(m.parameters(i) - truth(i)), 4.0 * m.parameter_std(i)) << "param " << i;
    EXPECT_LT(m.parameter_std(i), 0.01) << "param " << i;  // a precise fit on 5000 samples
  }
  EXPECT_NEAR(m.loss, 0.01, 0.0006);  // chi2 spread: 0.01 * sqrt(2/5000) = 2e-4 -> 3 sigma
  EXPECT_NEAR(m.noise_variance, m.loss * 4995.0 / 4988.0, 1e-15);
  EXPECT_NEAR(m.aic, std::log(m.loss) + 2.0 * 7.0 / 4995.0, 1e-12);
  EXPECT_NEAR(m.fpe, m.loss * (1.0 + 7.0 / 4995.0) / (1.0 - 7.0 / 4995.0), 1e-15);
}

TEST(Arx, StandardDeviationsMatchMonteCarloSpread) {
  // 400 independent noise realisations on one fixed input record: the sample standard deviation
  // of each estimate must match the mean reported one.  The sample std of 400 draws has a
  // relative spread of about 1/sqrt(800) = 3.5 %, so +-15 % is a > 4 sigma band.
  const int runs = 400;
  const Data base = Generate(1000, 0.0, 3);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal(0.0, 0.2);
  const Truth truth;
  Eigen::MatrixXd estimates(runs, 7);
  Eigen::VectorXd reported = Eigen::VectorXd::Zero(7);
  for (int r = 0; r < runs; ++r) {
    Eigen::VectorXd y = Eigen::VectorXd::Zero(1000);
    auto yp = [&](int t) { return t >= 0 ? y(t) : 0.0; };
    auto up = [&](int t, int i) { return t >= 0 ? base.u(t, i) : 0.0; };
    for (int t = 0; t < 1000; ++t) {
      y(t) = -truth.a[0] * yp(t - 1) - truth.a[1] * yp(t - 2) + truth.b1[0] * up(t - 1, 0) +
             truth.b1[1] * up(t - 2, 0) + truth.b2[0] * up(t - 3, 1) + truth.b2[1] * up(t - 4, 1) +
             truth.b2[2] * up(t - 5, 1) + normal(rng);
    }
    const ArxModel m = FitArx(y, base.u, TruthOrders());
    estimates.row(r) = m.parameters.transpose();
    reported += m.parameter_std / runs;
  }
  const Eigen::RowVectorXd mean = estimates.colwise().mean();
  for (int i = 0; i < 7; ++i) {
    const double spread =
        std::sqrt((estimates.col(i).array() - mean(i)).square().sum() / (runs - 1));
    EXPECT_NEAR(spread / reported(i), 1.0, 0.15) << "param " << i;
  }
}

TEST(Arx, SimulationReproducesNoiseFreeDataAndPredictionGivesTheResiduals) {
  const Data clean = Generate(300, 0.0, 5);
  const ArxModel exact = FitArx(clean.y, clean.u, TruthOrders());
  // The generator started from rest, as SimulateArx does without y_initial.
  EXPECT_LT((SimulateArx(exact, clean.u) - clean.y).cwiseAbs().maxCoeff(), 1e-8);

  const Data noisy = Generate(2000, 0.05, 6);
  const ArxModel m = FitArx(noisy.y, noisy.u, TruthOrders());
  const Eigen::VectorXd y_hat = PredictArx(m, noisy.y, noisy.u);
  const Eigen::VectorXd e = (noisy.y - y_hat).tail(m.num_samples);
  EXPECT_NEAR(e.squaredNorm() / static_cast<double>(m.num_samples), m.loss, 1e-14);
  // Simulation of a noisy-data model from the first measured outputs stays close to the
  // noise-free response of the true system (noise is small, the model is accurate).
  const Eigen::VectorXd y_sim = SimulateArx(m, noisy.u, noisy.y.head(5));
  EXPECT_EQ(y_sim.head(5), noisy.y.head(5));
  Data truth = Generate(2000, 0.0, 6);  // same inputs: same seed, the noise draws come after
  const double rms = std::sqrt((y_sim - truth.y).tail(1900).squaredNorm() / 1900.0);
  EXPECT_LT(rms, 0.1);
}

TEST(Arx, StaticFitOnAnIntegratedInputWithOffset) {
  // The integrator-delay fit: level = b * sum(q_tot) + c, as ARX with na = 0, one
  // input (the integrated flow, nb = 1, nk = 0) and a constant input for the offset.
  const int n = 200;
  Eigen::MatrixXd u(n, 2);
  double sum = 0.0;
  for (int t = 0; t < n; ++t) {
    sum += std::sin(0.05 * t) + 0.3;
    u(t, 0) = sum;
    u(t, 1) = 1.0;
  }
  const Eigen::VectorXd y = (0.012 * u.col(0)).array() + 1.85;
  ArxOrders o;
  o.na = 0;
  o.nb = {1, 1};
  o.nk = {0, 0};
  const ArxModel m = FitArx(y, u, o);
  EXPECT_EQ(m.first_sample, 0);
  EXPECT_NEAR(m.b[0](0), 0.012, 1e-12);
  EXPECT_NEAR(m.b[1](0), 1.85, 1e-10);
}

TEST(Arx, LaterFirstSampleUsesFewerEquations) {
  const Data d = Generate(400, 0.01, 8);
  const ArxModel m = FitArx(d.y, d.u, TruthOrders(), 20);
  EXPECT_EQ(m.first_sample, 20);
  EXPECT_EQ(m.num_samples, 380);
  // Same as fitting the tail of the data with its own default window starting 15 samples later.
  const ArxModel tail = FitArx(d.y.tail(385), d.u.bottomRows(385), TruthOrders());
  EXPECT_LT((m.parameters - tail.parameters).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Arx, RejectsBadArguments) {
  const Data d = Generate(100, 0.01, 9);
  ArxOrders o = TruthOrders();
  o.nb = {2};
  EXPECT_THROW(FitArx(d.y, d.u, o), std::invalid_argument);  // nb size
  o = TruthOrders();
  o.na = -1;
  EXPECT_THROW(FitArx(d.y, d.u, o), std::invalid_argument);
  o = TruthOrders();
  o.nk = {1, -2};
  EXPECT_THROW(FitArx(d.y, d.u, o), std::invalid_argument);
  o = TruthOrders();
  EXPECT_THROW(FitArx(d.y, d.u, o, 4), std::invalid_argument);  // before min_first_sample
  EXPECT_THROW(FitArx(d.y.head(10), d.u.topRows(10), o), std::invalid_argument);  // 5 rows < 7
  EXPECT_THROW(FitArx(d.y.head(99), d.u, o), std::invalid_argument);              // size mismatch
  Eigen::MatrixXd zero_input = d.u;
  zero_input.col(1).setZero();
  EXPECT_THROW(FitArx(d.y, zero_input, o), std::invalid_argument);  // rank deficient
  Eigen::VectorXd bad = d.y;
  bad(50) = std::nan("");
  EXPECT_THROW(FitArx(bad, d.u, o), std::invalid_argument);
  ArxOrders none;
  none.na = 0;
  none.nb = {0, 0};
  none.nk = {1, 1};
  EXPECT_THROW(FitArx(d.y, d.u, none), std::invalid_argument);
  const ArxModel m = FitArx(d.y, d.u, o);
  EXPECT_THROW(SimulateArx(m, d.u.leftCols(1)), std::invalid_argument);
  EXPECT_THROW(PredictArx(m, d.y.head(50), d.u), std::invalid_argument);
}

// The message of the std::invalid_argument `f` throws ("" when it throws none).
template <class F>
std::string ThrownMessage(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// Regression: `--nk 2147483647` made min_first_sample() = nb + nk - 1 overflow to a negative
// first sample and FitArx read before the record (SIGSEGV); --nb 2147483647 made na + sum(nb)
// wrap to 0 ("needs a parameter", the wrong reason).  Each order is now range-checked by name.
TEST(Arx, RejectsOrdersBeyondTheirBoundsNamingThem) {
  const Data d = Generate(100, 0.01, 9);
  ArxOrders o = TruthOrders();
  o.nk = {1, 2147483647};
  EXPECT_NE(ThrownMessage([&] {
              FitArx(d.y, d.u, o);
            }).find("ArxOrders.nk[1] = 2147483647 is out of range (allowed: 0..10000000)"),
            std::string::npos);
  o = TruthOrders();
  o.nb = {2147483647, 3};
  EXPECT_NE(ThrownMessage([&] {
              FitArx(d.y, d.u, o);
            }).find("ArxOrders.nb[0] = 2147483647 is out of range (allowed: 0..1000)"),
            std::string::npos);
  o = TruthOrders();
  o.na = 2147483647;
  EXPECT_NE(ThrownMessage([&] { FitArx(d.y, d.u, o); }).find("ArxOrders.na = 2147483647"),
            std::string::npos);
  o = TruthOrders();
  o.na = 1000;
  o.nb = {1000, 3};
  EXPECT_NE(ThrownMessage([&] {
              FitArx(d.y, d.u, o);
            }).find("na + sum(nb) = 2003 is out of range (allowed: 1..1000)"),
            std::string::npos);
  // At the bound the orders are valid; the record is then too short, said as such.
  o = TruthOrders();
  o.nk = {1, kMaxArxDelaySamples};
  EXPECT_NE(ThrownMessage([&] { FitArx(d.y, d.u, o); }).find("equations for"), std::string::npos);
}

}  // namespace
}  // namespace canalid::core
