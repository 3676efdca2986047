#include "core/online/online_arx.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <vector>

#include "tests/core/online_test_data.h"

namespace canalid::core {
namespace {

struct ArxData {
  std::vector<double> u;
  std::vector<double> y;
};

// y(k) = 1.5 y(k-1) - 0.7 y(k-2) + 0.5 u(k-3) + 0.3 u(k-4) + e(k): na = 2, nb = 2, nk = 3,
// i.e. a = [-1.5, 0.7], b = [0.5, 0.3] in MATLAB's convention.
ArxData MakeArx(int samples, double noise, std::uint64_t seed) {
  const std::vector<double> u = testdata::Prbs(samples, 5, seed);
  testdata::TestRandom rnd(seed + 7);
  ArxData d{u, std::vector<double>(static_cast<std::size_t>(samples), 0.0)};
  for (int k = 0; k < samples; ++k) {
    const auto at = [&](const std::vector<double>& v, int j) {
      return j >= 0 ? v[static_cast<std::size_t>(j)] : 0.0;
    };
    d.y[static_cast<std::size_t>(k)] = 1.5 * at(d.y, k - 1) - 0.7 * at(d.y, k - 2) +
                                       0.5 * at(u, k - 3) + 0.3 * at(u, k - 4) +
                                       noise * rnd.Normal();
  }
  return d;
}

// Independent batch ARX on the rows k = k_start..N-1 by Householder QR.
Eigen::VectorXd BatchArx(const ArxData& d, int na, int nb, int nk, int k_start) {
  const int rows = static_cast<int>(d.y.size()) - k_start;
  Eigen::MatrixXd a(rows, na + nb);
  Eigen::VectorXd y(rows);
  for (int r = 0; r < rows; ++r) {
    const int k = k_start + r;
    for (int i = 0; i < na; ++i) a(r, i) = -d.y[static_cast<std::size_t>(k - 1 - i)];
    for (int j = 0; j < nb; ++j) a(r, na + j) = d.u[static_cast<std::size_t>(k - nk - j)];
    y(r) = d.y[static_cast<std::size_t>(k)];
  }
  return a.householderQr().solve(y);
}

OnlineArxOptions Options(double lambda) {
  OnlineArxOptions o;
  o.na = 2;
  o.nb = 2;
  o.min_delay_samples = 1;
  o.max_delay_samples = 6;
  o.rls.forgetting = lambda;
  o.rls.initial_covariance = 1e8;
  return o;
}

// lambda = 1, P0 = 1e8: the prior contributes ~1e-8 against an information matrix with smallest
// eigenvalue O(10) over 2000 rows, so 1e-6 relative has orders of margin.
TEST(OnlineArxBank, ForgettingOneEqualsBatchLeastSquaresForEveryDelay) {
  const ArxData d = MakeArx(2000, 0.05, 3);
  OnlineArxBank bank(Options(1.0));
  for (std::size_t k = 0; k < d.y.size(); ++k) bank.Update(d.u[k], d.y[k]);
  const int k_start = std::max(2, 6 + 2 - 1);
  for (int nk = 1; nk <= 6; ++nk) {
    const Eigen::VectorXd batch = BatchArx(d, 2, 2, nk, k_start);
    const ArxSnapshot s = bank.CandidateSnapshot(nk);
    Eigen::VectorXd online(4);
    online << s.a, s.b;
    for (int i = 0; i < 4; ++i) {
      EXPECT_LT(std::abs(online(i) - batch(i)) / std::abs(batch(i)), 1e-6) << nk << " " << i;
    }
  }
  const ArxSnapshot s = bank.Snapshot();
  EXPECT_EQ(s.delay_samples, 3);
  EXPECT_NEAR(s.a(0), -1.5, 4.0 * s.a_std(0));
  EXPECT_NEAR(s.b(1), 0.3, 4.0 * s.b_std(1));
}

// Bad samples: every regression containing one is skipped, so the result equals batch least
// squares on the remaining rows.
TEST(OnlineArxBank, BadSamplesNeverEnterARegression) {
  const ArxData d = MakeArx(1500, 0.05, 5);
  OnlineArxOptions o = Options(1.0);
  o.min_delay_samples = 3;
  o.max_delay_samples = 3;
  OnlineArxBank bank(o);
  const int k_start = 4;
  std::vector<bool> use(d.y.size(), true);
  for (std::size_t k = 0; k < d.y.size(); ++k) {
    double u = d.u[k];
    double y = d.y[k];
    const int ki = static_cast<int>(k);
    if (ki % 97 == 50) {
      y = std::numeric_limits<double>::quiet_NaN();
      for (int j = 0; j <= 2; ++j)
        use[k + static_cast<std::size_t>(j)] = false;  // y(k), y(k-1), y(k-2)
    }
    // A dropout of three inputs: a row reading the first one comes after the last bad input, so
    // the most recent bad sample alone cannot tell it is poisoned.
    if (ki % 89 >= 40 && ki % 89 <= 42) {
      u = 1e12;                                                                   // absurd
      for (int j = 3; j <= 4; ++j) use[k + static_cast<std::size_t>(j)] = false;  // u(k-3), u(k-4)
    }
    bank.Update(u, y);
  }
  const int rows_total = static_cast<int>(d.y.size()) - k_start;
  std::vector<int> kept;
  for (int k = k_start; k < static_cast<int>(d.y.size()); ++k) {
    if (use[static_cast<std::size_t>(k)]) kept.push_back(k);
  }
  ASSERT_LT(static_cast<int>(kept.size()), rows_total);
  Eigen::MatrixXd a(static_cast<int>(kept.size()), 4);
  Eigen::VectorXd y(static_cast<int>(kept.size()));
  for (int r = 0; r < a.rows(); ++r) {
    const auto k = static_cast<std::size_t>(kept[static_cast<std::size_t>(r)]);
    a.row(r) << -d.y[k - 1], -d.y[k - 2], d.u[k - 3], d.u[k - 4];
    y(r) = d.y[k];
  }
  const Eigen::VectorXd batch = a.householderQr().solve(y);
  const ArxSnapshot s = bank.CandidateSnapshot(3);
  EXPECT_LT(std::abs(s.a(0) - batch(0)) / std::abs(batch(0)), 1e-6);
  EXPECT_LT(std::abs(s.b(0) - batch(2)) / std::abs(batch(2)), 1e-6);
  EXPECT_GT(bank.health().bad_outputs, 10);
  EXPECT_GT(bank.health().bad_inputs, 10);
}

TEST(OnlineArxBank, SameSamplesGiveBitIdenticalSnapshots) {
  const ArxData d = MakeArx(800, 0.05, 9);
  OnlineArxBank a(Options(0.99));
  OnlineArxBank b(Options(0.99));
  for (std::size_t k = 0; k < d.y.size(); ++k) {
    a.Update(d.u[k], d.y[k]);
    b.Update(d.u[k], d.y[k]);
  }
  for (int nk = 1; nk <= 6; ++nk) {
    const ArxSnapshot sa = a.CandidateSnapshot(nk);
    const ArxSnapshot sb = b.CandidateSnapshot(nk);
    for (int i = 0; i < 2; ++i) {
      EXPECT_EQ(sa.a(i), sb.a(i));
      EXPECT_EQ(sa.b(i), sb.b(i));
    }
    EXPECT_EQ(sa.loss, sb.loss);
  }
}

}  // namespace
}  // namespace canalid::core
