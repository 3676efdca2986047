#include "core/online/online_lpv.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <vector>

#include "tests/core/online_test_data.h"

namespace canalid::core {
namespace {

// y(k) = -a(s) y(k-1) + b(s) u(k-1) + e, a(s) = -0.8 - 0.1 s + 0.05 s^2, b(s) = 0.5 + 0.3 s^2,
// with s(k) sweeping slowly over [0, 1] (an operating point such as the upstream level).
struct LpvData {
  std::vector<double> u, y, s;
};

double TrueA(double s) { return -0.8 - 0.1 * s + 0.05 * s * s; }
double TrueB(double s) { return 0.5 + 0.3 * s * s; }

LpvData MakeLpv(int samples) {
  LpvData d{testdata::Prbs(samples, 4, 51), std::vector<double>(static_cast<std::size_t>(samples)),
            std::vector<double>(static_cast<std::size_t>(samples))};
  testdata::TestRandom rnd(53);
  double y = 0.0;
  for (int k = 0; k < samples; ++k) {
    const auto uk = static_cast<std::size_t>(k);
    d.s[uk] = 0.5 + 0.5 * std::sin(2.0 * M_PI * k / 1000.0);
    if (k >= 1) y = -TrueA(d.s[uk]) * y + TrueB(d.s[uk]) * d.u[uk - 1] + 0.01 * rnd.Normal();
    d.y[uk] = y;
  }
  return d;
}

// lambda = 1, P0 = 1e8: equal to batch QR on the expanded rows (1e-6 relative), and the local
// models at s = 0, 0.5, 1 within 0.01 of the truth.
TEST(OnlineLpvArx, EqualsBatchAndRecoversTheQuadraticScheduling) {
  const LpvData d = MakeLpv(4000);
  OnlineLpvArxOptions o;
  o.rls.initial_covariance = 1e8;
  OnlineLpvArx lpv(o);
  for (std::size_t k = 0; k < d.y.size(); ++k) lpv.Update(d.u[k], d.y[k], d.s[k]);
  const int rows = static_cast<int>(d.y.size()) - 1;
  Eigen::MatrixXd a(rows, 6);
  Eigen::VectorXd y(rows);
  for (int r = 0; r < rows; ++r) {
    const auto k = static_cast<std::size_t>(r) + 1;
    const double s = d.s[k];
    a.row(r) << -d.y[k - 1], -d.y[k - 1] * s, -d.y[k - 1] * s * s, d.u[k - 1], d.u[k - 1] * s,
        d.u[k - 1] * s * s;
    y(r) = d.y[k];
  }
  const Eigen::VectorXd batch = a.householderQr().solve(y);
  const Eigen::VectorXd& th = lpv.estimator().theta();
  for (int i = 0; i < 6; ++i) {
    EXPECT_LT(std::abs(th(i) - batch(i)), 1e-6 * batch.norm()) << i;
  }
  for (double s : {0.0, 0.5, 1.0}) {
    ArxParamVector pa;
    ArxParamVector pb;
    lpv.ParametersAt(s, pa, pb);
    EXPECT_NEAR(pa(0), TrueA(s), 0.01) << s;
    EXPECT_NEAR(pb(0), TrueB(s), 0.01) << s;
  }
}

// NaN, Inf and absurd u, y or s: every regression that would contain one is left out, and the
// estimate equals batch QR on exactly the remaining rows (1e-6 relative, as above); a bad sample
// never reaches the state (it stays finite).
TEST(OnlineLpvArx, BadSamplesNeverEnterARegression) {
  const LpvData d = MakeLpv(4000);
  OnlineLpvArxOptions o;
  o.rls.initial_covariance = 1e8;
  o.input_abs_max = 100.0;
  o.output_abs_max = 100.0;
  o.scheduling_abs_max = 100.0;
  OnlineLpvArx lpv(o);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u = d.u;
  std::vector<double> y = d.y;
  std::vector<double> s = d.s;
  for (std::size_t k = 10; k < d.y.size(); ++k) {
    if (k % 41 == 0) u[k] = nan;
    if (k % 59 == 0) y[k] = -inf;
    if (k % 67 == 0) y[k] = 1e6;  // absurd
    if (k % 73 == 0) s[k] = nan;
    if (k % 79 == 0) s[k] = 1e6;
  }
  auto good = [](double v) { return std::isfinite(v) && std::abs(v) <= 100.0; };
  int updates = 0;
  for (std::size_t k = 0; k < d.y.size(); ++k) updates += lpv.Update(u[k], y[k], s[k]) ? 1 : 0;
  // Row k (na = nb = nk = 1) uses y(k), y(k-1), u(k-1), s(k).
  std::vector<int> rows_used;
  for (std::size_t k = 1; k < d.y.size(); ++k) {
    if (good(y[k]) && good(y[k - 1]) && good(u[k - 1]) && good(s[k])) {
      rows_used.push_back(static_cast<int>(k));
    }
  }
  ASSERT_GT(rows_used.size(), 3000u);
  EXPECT_EQ(updates, static_cast<int>(rows_used.size()));
  Eigen::MatrixXd a(static_cast<Eigen::Index>(rows_used.size()), 6);
  Eigen::VectorXd target(a.rows());
  for (Eigen::Index r = 0; r < a.rows(); ++r) {
    const auto k = static_cast<std::size_t>(rows_used[static_cast<std::size_t>(r)]);
    const double sk = s[k];
    a.row(r) << -y[k - 1], -y[k - 1] * sk, -y[k - 1] * sk * sk, u[k - 1], u[k - 1] * sk,
        u[k - 1] * sk * sk;
    target(r) = y[k];
  }
  const Eigen::VectorXd batch = a.householderQr().solve(target);
  const Eigen::VectorXd& th = lpv.estimator().theta();
  ASSERT_TRUE(th.allFinite());
  for (int i = 0; i < 6; ++i) EXPECT_LT(std::abs(th(i) - batch(i)), 1e-6 * batch.norm()) << i;
}

TEST(LpvExpand, IsTheKroneckerProduct) {
  Eigen::Vector2d phi(2.0, -1.0);
  Eigen::Matrix<double, 6, 1> out;
  LpvExpand(phi, 3.0, out);
  Eigen::Matrix<double, 6, 1> expected;
  expected << 2.0, 6.0, 18.0, -1.0, -3.0, -9.0;
  EXPECT_EQ(out, expected);
}

}  // namespace
}  // namespace canalid::core
