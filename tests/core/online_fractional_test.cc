#include "core/online/online_fractional.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/online/online_gl_regressor.h"
#include "tests/core/online_test_data.h"

namespace canalid::core {
namespace {

constexpr double kH = 0.5;
constexpr int kMemory = 200;
constexpr int kDelay = 2;

// GL weights written out independently of OnlineGlRegressor: w_j = (-1)^j binom(alpha, j).
std::vector<double> Binomial(double alpha, int memory) {
  std::vector<double> w(static_cast<std::size_t>(memory) + 1);
  for (int j = 0; j <= memory; ++j) {
    double b = 1.0;  // binom(alpha, j) = prod_{i=0..j-1} (alpha - i) / (i + 1)
    for (int i = 0; i < j; ++i) b *= (alpha - i) / (i + 1);
    w[static_cast<std::size_t>(j)] = (j % 2 == 0 ? 1.0 : -1.0) * b;
  }
  return w;
}

struct Data {
  std::vector<double> u;
  std::vector<double> x;  // the unit-gain simulation
  std::vector<double> y;
};

// The GL1 simulation of e^{-d h s} / (1 + T s^alpha), written out (docs/references.md):
// x(k) = (u(k-d) - c sum_{j=1..L} w_j x(k-j)) / (1 + c), c = T h^-alpha.
std::vector<double> SimulateUnit(const std::vector<double>& u, double alpha, double time_constant) {
  const std::vector<double> w = Binomial(alpha, kMemory);
  const double c = time_constant * std::pow(kH, -alpha);
  std::vector<double> x(u.size());
  for (std::size_t k = 0; k < u.size(); ++k) {
    double s = 0.0;
    for (std::size_t j = 1; j <= std::min<std::size_t>(kMemory, k); ++j) s += w[j] * x[k - j];
    const double input = k >= kDelay ? u[k - kDelay] : 0.0;
    x[k] = (input - c * s) / (1.0 + c);
  }
  return x;
}

// y = K x + offset + white output noise.
Data Simulate(double alpha, double gain, double time_constant, double offset, int samples,
              double noise) {
  Data d{testdata::Prbs(samples, 20, 17), {}, {}};
  d.x = SimulateUnit(d.u, alpha, time_constant);
  testdata::TestRandom rnd(23);
  for (double x : d.x) d.y.push_back(gain * x + offset + noise * rnd.Normal());
  return d;
}

OnlineFractionalOptions Options() {
  OnlineFractionalOptions o;
  o.sample_time_s = kH;
  o.memory_samples = kMemory;
  o.delay_samples = kDelay;
  o.rls.initial_covariance = 1e10;
  return o;
}

// The index of the grid point of alpha `a` nearest to the characteristic time `tc`.
int NearestCandidate(const OnlineFractionalOptions& o, std::size_t a, double tc) {
  int best = 0;
  for (int t = 1; t < o.num_time_points(); ++t) {
    if (std::abs(std::log(o.characteristic_time_s(t) / tc)) <
        std::abs(std::log(o.characteristic_time_s(best) / tc))) {
      best = t;
    }
  }
  return static_cast<int>(a) * o.num_time_points() + best;
}

TEST(OnlineGlRegressor, WeightsAreSignedBinomials) {
  const std::vector<double> w = Binomial(0.7, 30);
  OnlineGlRegressor gl(0.7, 30);
  for (int j = 0; j <= 30; ++j) EXPECT_NEAR(gl.weight(j), w[static_cast<std::size_t>(j)], 1e-14);
  // alpha = 1: the first difference.
  OnlineGlRegressor first(1.0, 5);
  EXPECT_DOUBLE_EQ(first.weight(1), -1.0);
  EXPECT_DOUBLE_EQ(first.weight(2), 0.0);
  EXPECT_THROW(OnlineGlRegressor(2.5, 10), std::invalid_argument);
}

// Sum against the sum written out (lag by lag, newest first) while the history fills and wraps:
// equal to rounding (Sum adds in another order, in vector lanes).
TEST(OnlineGlRegressor, SumEqualsTheWrittenOutSumAtEveryFillAndWrap) {
  constexpr int kTerms = 37;
  const std::vector<double> w = Binomial(0.63, kTerms);
  OnlineGlRegressor gl(0.63, kTerms);
  RingBuffer<double> history(kTerms + 5);
  testdata::TestRandom rnd(5);
  for (int k = 0; k < 200; ++k) {
    double want = 0.0, scale = 0.0;
    for (int j = 1; j <= std::min(kTerms, history.size()); ++j) {
      want += w[static_cast<std::size_t>(j)] * history[j - 1];
      scale += std::abs(w[static_cast<std::size_t>(j)] * history[j - 1]);
    }
    ASSERT_NEAR(gl.Sum(history), want, 1e-14 * scale + 1e-300) << "k = " << k;
    history.Push(1.0 + rnd.Normal());
  }
}

TEST(OnlineFractionalOptions, TheGridSpansTheMemoryAtTenPointsPerDecade) {
  OnlineFractionalOptions o = Options();  // L = 200: 2.3 decades
  ASSERT_EQ(o.num_time_points(), 25);
  EXPECT_DOUBLE_EQ(o.characteristic_time_s(0), kH);
  EXPECT_NEAR(o.characteristic_time_s(24), kMemory * kH, 1e-12);
  EXPECT_NEAR(o.characteristic_time_s(1) / o.characteristic_time_s(0), std::pow(200.0, 1.0 / 24),
              1e-12);
  o.memory_samples = 3;  // at least a decade
  EXPECT_EQ(o.num_time_points(), 11);
  EXPECT_NEAR(o.characteristic_time_s(10), 10 * kH, 1e-12);
  o.memory_samples = 1000000;  // 8 alphas x 1e6 samples x 61 points: refused, and said why
  try {
    o.Validate();
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("memory_samples"), std::string::npos) << e.what();
  }
}

// With lambda = 1 and P0 = 1e10 every candidate is the least-squares fit of y on its own
// simulated output and a constant: the candidate at (0.7, the nearest grid tc) equals QR on the
// test's own GL simulation at that tc (1e-6).
TEST(OnlineFractionalBank, EachCandidateIsTheLeastSquaresFitOnItsSimulation) {
  const Data d = Simulate(0.7, 2.0, 5.0, 0.3, 3000, 0.005);
  const OnlineFractionalOptions o = Options();
  OnlineFractionalBank bank(o);
  for (std::size_t k = 0; k < d.y.size(); ++k) bank.Update(d.u[k], d.y[k]);

  for (int index : {NearestCandidate(o, 2, 4.0), NearestCandidate(o, 5, 20.0)}) {
    const FractionalSnapshot c = bank.CandidateSnapshot(index);
    const double tc = o.characteristic_time_s(index % o.num_time_points());
    ASSERT_DOUBLE_EQ(c.time_constant_s, std::pow(tc, c.alpha));
    const std::vector<double> x = SimulateUnit(d.u, c.alpha, c.time_constant_s);
    const int n = static_cast<int>(d.y.size());
    Eigen::MatrixXd a(n, 2);
    Eigen::VectorXd y(n);
    for (int k = 0; k < n; ++k) {
      a(k, 0) = x[static_cast<std::size_t>(k)];
      a(k, 1) = 1.0;
      y(k) = d.y[static_cast<std::size_t>(k)];
    }
    const Eigen::VectorXd batch = a.householderQr().solve(y);
    EXPECT_LT(std::abs(c.gain - batch(0)) / std::abs(batch(0)), 1e-6) << "alpha " << c.alpha;
    EXPECT_LT(std::abs(c.offset - batch(1)) / std::abs(batch(1)), 1e-6) << "alpha " << c.alpha;
    EXPECT_NEAR(c.loss, (y - a * batch).squaredNorm(), 1e-6 * c.loss);
  }
}

// The bank selects the true alpha and, between grid points, the parabola through the losses
// finds T: the truth's tc = T^(1/alpha) = 9.97 s lies half way between two grid points (8.84 and
// 11.0 s), whose T are 8 and 7 % off.
TEST(OnlineFractionalBank, FindsAlphaAndTheTimeConstantBetweenGridPoints) {
  constexpr double kT = 5.0;
  const Data d = Simulate(0.7, 2.0, kT, 0.3, 3000, 0.005);
  const OnlineFractionalOptions o = Options();
  OnlineFractionalBank bank(o);
  for (std::size_t k = 0; k < d.y.size(); ++k) bank.Update(d.u[k], d.y[k]);

  const FractionalSnapshot s = bank.Snapshot();
  ASSERT_TRUE(s.valid);
  EXPECT_DOUBLE_EQ(s.alpha, 0.7);
  EXPECT_FALSE(s.at_grid_edge);
  const FractionalSnapshot grid = bank.CandidateSnapshot(bank.selected_index());
  EXPECT_GT(std::abs(grid.time_constant_s - kT), 0.06 * kT) << grid.time_constant_s;
  EXPECT_NEAR(s.time_constant_s, kT, 0.01 * kT);
  EXPECT_NEAR(s.gain, 2.0, 0.01 * 2.0);
  EXPECT_NEAR(s.offset, 0.3, 0.002);
  // The standard deviations are of the size of the errors: not zero, not huge.
  EXPECT_GT(s.time_constant_std_s, 1e-4 * kT);
  EXPECT_LT(s.time_constant_std_s, 0.05 * kT);
  EXPECT_GT(s.gain_std, 0.0);
  EXPECT_LT(s.gain_std, 0.02);
}

// With an update law that is not least squares (Kalman) the selector compares prediction errors,
// whose weighted means give no variance: T is still refined, its deviation is not given.
TEST(OnlineFractionalBank, ANonLeastSquaresLawGivesNoTimeConstantDeviation) {
  const Data d = Simulate(0.7, 2.0, 5.0, 0.3, 3000, 0.005);
  OnlineFractionalOptions o = Options();
  o.rls.method = RlsMethod::kKalman;
  OnlineFractionalBank bank(o);
  for (std::size_t k = 0; k < d.y.size(); ++k) bank.Update(d.u[k], d.y[k]);
  const FractionalSnapshot s = bank.Snapshot();
  ASSERT_TRUE(s.valid);
  EXPECT_DOUBLE_EQ(s.alpha, 0.7);
  EXPECT_TRUE(std::isnan(s.time_constant_std_s));
  EXPECT_NEAR(s.time_constant_s, 5.0, 0.05 * 5.0);
}

// A plant slower than the grid's longest characteristic time: the bank says T is a bound.
TEST(OnlineFractionalBank, APlantSlowerThanTheGridIsFlaggedAtItsEdge) {
  const Data d = Simulate(0.9, 1.0, 400.0, 0.0, 3000, 0.001);  // tc = 780 s > 100 s
  OnlineFractionalBank bank(Options());
  for (std::size_t k = 0; k < d.y.size(); ++k) bank.Update(d.u[k], d.y[k]);
  const FractionalSnapshot s = bank.Snapshot();
  ASSERT_TRUE(s.valid);
  EXPECT_TRUE(s.at_grid_edge);
  EXPECT_TRUE(std::isnan(s.time_constant_std_s));
}

TEST(OnlineFractionalBank, BadSamplesDoNotCorruptTheFit) {
  const Data d = Simulate(0.9, 1.5, 3.0, 0.0, 3000, 0.005);
  OnlineFractionalBank bank(Options());
  for (std::size_t k = 0; k < d.y.size(); ++k) {
    double y = d.y[k];
    double u = d.u[k];
    if (k % 101 == 33) y = std::numeric_limits<double>::quiet_NaN();
    if (k % 131 == 66) y = std::numeric_limits<double>::infinity();
    if (k % 151 == 77) u = std::numeric_limits<double>::quiet_NaN();
    bank.Update(u, y);
  }
  EXPECT_GT(bank.health().bad_outputs, 40);
  EXPECT_GT(bank.health().bad_inputs, 15);
  const FractionalSnapshot s = bank.Snapshot();
  EXPECT_DOUBLE_EQ(s.alpha, 0.9);
  // A held input differs from the truth for one sample in 151: a few % on K and T is expected.
  EXPECT_NEAR(s.gain, 1.5, 0.05);
  EXPECT_NEAR(s.time_constant_s, 3.0, 0.15);
}

TEST(OnlineFractionalBank, SameSamplesGiveBitIdenticalSnapshots) {
  const Data d = Simulate(0.6, 1.0, 2.0, 0.0, 600, 0.01);
  OnlineFractionalOptions o = Options();
  o.rls.forgetting = 0.995;
  OnlineFractionalBank a(o);
  OnlineFractionalBank b(o);
  for (std::size_t k = 0; k < d.y.size(); ++k) {
    a.Update(d.u[k], d.y[k]);
    b.Update(d.u[k], d.y[k]);
  }
  for (int i = 0; i < a.num_candidates(); ++i) {
    EXPECT_EQ(a.CandidateSnapshot(i).gain, b.CandidateSnapshot(i).gain);
    EXPECT_EQ(a.CandidateSnapshot(i).offset, b.CandidateSnapshot(i).offset);
    EXPECT_EQ(a.CandidateSnapshot(i).loss, b.CandidateSnapshot(i).loss);
  }
  EXPECT_EQ(a.Snapshot().time_constant_s, b.Snapshot().time_constant_s);
}

}  // namespace
}  // namespace canalid::core
