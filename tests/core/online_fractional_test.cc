#include "core/online/online_fractional.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <vector>

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
  std::vector<double> y;
};

// GL1 simulation of K e^{-d h s} / (1 + T s^alpha) with equation noise (docs/references.md):
// y(k) = (K u(k-d) - c sum_{j=1..L} w_j y(k-j)) / (1 + c) + e(k), c = T h^-alpha.
Data Simulate(double alpha, double gain, double time_constant, int samples, double noise) {
  const std::vector<double> w = Binomial(alpha, kMemory);
  const double c = time_constant * std::pow(kH, -alpha);
  Data d{testdata::Prbs(samples, 20, 17), std::vector<double>(static_cast<std::size_t>(samples))};
  testdata::TestRandom rnd(23);
  for (int k = 0; k < samples; ++k) {
    double s = 0.0;
    for (int j = 1; j <= std::min(kMemory, k); ++j) {
      s += w[static_cast<std::size_t>(j)] * d.y[static_cast<std::size_t>(k - j)];
    }
    const double u = k >= kDelay ? d.u[static_cast<std::size_t>(k - kDelay)] : 0.0;
    d.y[static_cast<std::size_t>(k)] = (gain * u - c * s) / (1.0 + c) + noise * rnd.Normal();
  }
  return d;
}

OnlineFractionalOptions Options() {
  OnlineFractionalOptions o;
  o.sample_time_s = kH;
  o.memory_samples = kMemory;
  o.delay_samples = kDelay;
  o.rls.initial_covariance = 1e8;
  return o;
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

// With lambda = 1 the candidate at the true alpha equals batch QR on the same GL regressors
// (1e-6), the bank selects the true alpha 0.7, and K, T come back within 1 % (noise 0.005 on an
// output of amplitude ~2).
TEST(OnlineFractionalBank, EqualsBatchAndFindsAlpha) {
  const Data d = Simulate(0.7, 2.0, 5.0, 3000, 0.005);
  OnlineFractionalBank bank(Options());
  for (std::size_t k = 0; k < d.y.size(); ++k) bank.Update(d.u[k], d.y[k]);

  const std::vector<double> w = Binomial(0.7, kMemory);
  const int n = static_cast<int>(d.y.size());
  Eigen::MatrixXd a(n, 2);
  Eigen::VectorXd y(n);
  for (int k = 0; k < n; ++k) {
    double s = 0.0;
    for (int j = 1; j <= std::min(kMemory, k); ++j) {
      s += w[static_cast<std::size_t>(j)] * d.y[static_cast<std::size_t>(k - j)];
    }
    a(k, 0) = -s;
    a(k, 1) = k >= kDelay ? d.u[static_cast<std::size_t>(k - kDelay)] : 0.0;
    y(k) = d.y[static_cast<std::size_t>(k)];
  }
  const Eigen::VectorXd batch = a.householderQr().solve(y);
  const FractionalSnapshot c = bank.CandidateSnapshot(2);  // alpha = 0.7
  ASSERT_DOUBLE_EQ(c.alpha, 0.7);
  EXPECT_LT(std::abs(c.theta1 - batch(0)) / batch(0), 1e-6);
  EXPECT_LT(std::abs(c.theta2 - batch(1)) / batch(1), 1e-6);

  const FractionalSnapshot s = bank.Snapshot();
  EXPECT_DOUBLE_EQ(s.alpha, 0.7);
  EXPECT_NEAR(s.gain, 2.0, 0.02);
  EXPECT_NEAR(s.time_constant_s, 5.0, 0.05);
}

TEST(OnlineFractionalBank, BadSamplesDoNotCorruptTheFit) {
  const Data d = Simulate(0.9, 1.5, 3.0, 3000, 0.005);
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
  const Data d = Simulate(0.6, 1.0, 2.0, 600, 0.01);
  OnlineFractionalOptions o = Options();
  o.rls.forgetting = 0.995;
  OnlineFractionalBank a(o);
  OnlineFractionalBank b(o);
  for (std::size_t k = 0; k < d.y.size(); ++k) {
    a.Update(d.u[k], d.y[k]);
    b.Update(d.u[k], d.y[k]);
  }
  for (int i = 0; i < a.num_candidates(); ++i) {
    EXPECT_EQ(a.CandidateSnapshot(i).theta1, b.CandidateSnapshot(i).theta1);
    EXPECT_EQ(a.CandidateSnapshot(i).theta2, b.CandidateSnapshot(i).theta2);
    EXPECT_EQ(a.CandidateSnapshot(i).loss, b.CandidateSnapshot(i).loss);
  }
}

}  // namespace
}  // namespace canalid::core
