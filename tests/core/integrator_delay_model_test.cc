#include "core/integrator_delay/integrator_delay_model.h"

#include <gtest/gtest.h>

#include <Eigen/QR>

#include <cmath>
#include <random>

namespace canalid::core {
namespace {

// A seeded random binary inflow held for `clock` samples: enough to excite delay and area.
Eigen::VectorXd BinaryInflow(int n, double nominal, double amplitude, int clock, unsigned seed) {
  std::mt19937 rng(seed);
  Eigen::VectorXd q(n);
  double value = nominal;
  for (int k = 0; k < n; ++k) {
    if (k % clock == 0) value = nominal + ((rng() & 1U) ? amplitude : -amplitude);
    q(k) = value;
  }
  return q;
}

// The discrete ID difference equation itself generates the truth: y(k) - y(k-1) = b (q_in(k-nk) -
// q_out(k-1)).
Eigen::VectorXd IdLevel(const Eigen::VectorXd& q_in, const Eigen::VectorXd& q_out, double b, int nk,
                        double y0) {
  Eigen::VectorXd y(q_in.size());
  y(0) = y0;
  for (Eigen::Index k = 1; k < q_in.size(); ++k) {
    const double inflow = k - nk >= 0 ? q_in(k - nk) : q_in(0);
    y(k) = y(k - 1) + b * (inflow - q_out(k - 1));
  }
  return y;
}

TEST(IntegratorDelayModel, RecoversExactDelayAndAreaFromNoiseFreeData) {
  // ASCE canal 2 pool 2 at 10 m3/s: A = 34113 m2, tau = 682 s ~ 11 samples of 60 s.
  const double ts = 60.0, area = 34113.0;
  const int nk = 11, n = 840;
  const Eigen::VectorXd q_in = BinaryInflow(n, 10.0, 0.8, 6, 1);
  // Outflow with its own independent movement, so the outflow term is exercised too.
  const Eigen::VectorXd q_out = BinaryInflow(n, 10.0, 0.3, 17, 2);
  const Eigen::VectorXd y = IdLevel(q_in, q_out, ts / area, nk, 2.1);
  IntegratorDelayFitOptions options;
  options.max_nk = 40;
  options.closed_loop = ClosedLoopMode::kOff;
  const IntegratorDelayFit r = FitIntegratorDelay(q_in, q_out, y, ts, options);
  EXPECT_EQ(r.model.nk, nk);
  EXPECT_NEAR(r.model.area_m2(), area, 1e-9 * area);
  EXPECT_NEAR(r.model.delay_s(), 660.0, 1e-12);
  EXPECT_NEAR(r.drift_m_per_sample, 0.0, 1e-12);
  EXPECT_GT(r.metrics.fit_percent, 99.99999);
  EXPECT_TRUE(r.warnings.empty());
}

TEST(IntegratorDelayModel, StaysAccurateWithLevelNoiseAndDrift) {
  // 3 mm white noise and a 5 cm/day sensor drift: area within 3 %, delay within one sample.
  const double ts = 60.0, area = 34113.0;
  const int nk = 11, n = 840;
  const Eigen::VectorXd q_in = BinaryInflow(n, 10.0, 0.8, 6, 3);
  const Eigen::VectorXd q_out = Eigen::VectorXd::Constant(n, 10.0);
  Eigen::VectorXd y = IdLevel(q_in, q_out, ts / area, nk, 2.1);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (int k = 0; k < n; ++k) y(k) += noise(rng) + 0.05 * k * ts / 86400.0;
  IntegratorDelayFitOptions options;
  options.max_nk = 40;
  const IntegratorDelayFit r = FitIntegratorDelay(q_in, q_out, y, ts, options);
  EXPECT_FALSE(r.closed_loop) << r.closed_loop_reason;
  EXPECT_NEAR(r.model.nk, nk, 1);
  EXPECT_NEAR(r.model.area_m2(), area, 0.03 * area);
  EXPECT_NEAR(r.drift_m_per_sample, 0.05 * ts / 86400.0, 2e-5);
}

TEST(IntegratorDelayModel, ThreeStepMethodHandlesAFixedDownstreamGate) {
  // Closed loop: the outflow of a fixed gate follows the level, q_out = q0 + kw (y - y0). The
  // outflow column is computed from the *measured* level (as a PLC would), so its noise is the
  // level noise: correlated with the regression error. The three-step method must detect the
  // loop and stay within 5 %, and the IV cross-check within 10 %.
  const double ts = 60.0, area = 34113.0, b = ts / area, kw = 8.0;
  const int nk = 11, n = 1680;
  const Eigen::VectorXd q_in = BinaryInflow(n, 10.0, 0.8, 6, 9);
  std::mt19937 rng(13);
  std::normal_distribution<double> noise(0.0, 0.003);
  Eigen::VectorXd y(n), y_measured(n), q_out(n);
  y(0) = 2.1;
  for (int k = 0; k < n; ++k) {
    if (k > 0) {
      const double inflow = k - nk >= 0 ? q_in(k - nk) : q_in(0);
      y(k) = y(k - 1) + b * (inflow - (10.0 + kw * (y(k - 1) - 2.1)));
    }
    y_measured(k) = y(k) + noise(rng);
    q_out(k) = 10.0 + kw * (y_measured(k) - 2.1);
  }
  IntegratorDelayFitOptions options;
  options.max_nk = 40;
  const IntegratorDelayFit r = FitIntegratorDelay(q_in, q_out, y_measured, ts, options);
  EXPECT_TRUE(r.closed_loop) << r.closed_loop_reason;
  EXPECT_NEAR(r.model.nk, nk, 1);
  EXPECT_NEAR(r.model.area_m2(), area, 0.05 * area);
  EXPECT_NEAR(r.iv_area_m2, area, 0.10 * area);
}

TEST(IntegratorDelayModel, ScanLossesEqualFullQrFitsOfEachCandidate) {
  // The scan reduces each candidate to two detrended columns (Frisch-Waugh-Lovell); its losses
  // must equal the full 4-column QR fit wherever the wave-front coefficient is non-negative.
  const double ts = 60.0;
  const int n = 600;
  const Eigen::VectorXd q_in = BinaryInflow(n, 10.0, 0.8, 6, 21);
  const Eigen::VectorXd q_out = Eigen::VectorXd::Constant(n, 10.0);
  Eigen::VectorXd y = IdLevel(q_in, q_out, ts / 30000.0, 9, 2.0);
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (auto& v : y) v += noise(rng);
  IntegratorDelayFitOptions options;
  options.max_nk = 30;
  const IntegratorDelayFit r = FitIntegratorDelay(q_in, q_out, y, ts, options);
  int checked = 0;
  for (int nk = 0; nk <= 30; ++nk) {
    const Eigen::MatrixXd x = OpenLoopRegressors(q_in, q_out, nk, 31);
    const Eigen::VectorXd target = y.tail(n - 31);
    const Eigen::VectorXd theta = x.colPivHouseholderQr().solve(target);
    if (theta(1) < 0.0) continue;
    const double loss = (x * theta - target).squaredNorm() / static_cast<double>(target.size());
    EXPECT_NEAR(r.loss_by_nk(nk), loss, 1e-9 * loss) << "nk=" << nk;
    ++checked;
  }
  EXPECT_GT(checked, 5);
}

// The scan's losses come from running inner products of the raw columns; a long record with
// large flows and a gauge offset between inflow and outflow (so the integrated flow drifts by
// 2 m^3/s every sample, to 2e5 at the end) is where cancellation would show.  Against QR, the
// constrained candidates (p21 < 0, refitted without the column) included.
TEST(IntegratorDelayModel, ScanLossesHoldOnALongRecordWithLargeFlowsAndAnOffset) {
  const double ts = 10.0;
  const int n = 100000;
  const int first = 41;
  const Eigen::VectorXd q_in = BinaryInflow(n, 500.0, 5.0, 37, 5);
  const Eigen::VectorXd q_out = Eigen::VectorXd::Constant(n, 498.0);
  Eigen::VectorXd y = IdLevel(q_in, q_out, ts / 2.0e6, 17, 3.0);
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.002);
  for (auto& v : y) v += noise(rng);
  IntegratorDelayFitOptions options;
  options.max_nk = first - 1;
  const IntegratorDelayFit r = FitIntegratorDelay(q_in, q_out, y, ts, options);
  const Eigen::VectorXd target = y.tail(n - first);
  int best_nk = -1;
  double best_loss = 0.0;
  for (int nk = 0; nk < first; ++nk) {
    const Eigen::MatrixXd x = OpenLoopRegressors(q_in, q_out, nk, first);
    Eigen::VectorXd theta = x.colPivHouseholderQr().solve(target);
    double loss = (x * theta - target).squaredNorm();
    if (theta(1) < 0.0) {
      Eigen::MatrixXd reduced(x.rows(), 3);
      reduced << x.col(0), x.col(2), x.col(3);
      const Eigen::VectorXd t3 = reduced.colPivHouseholderQr().solve(target);
      loss = (reduced * t3 - target).squaredNorm();
    }
    loss /= static_cast<double>(target.size());
    EXPECT_NEAR(r.loss_by_nk(nk), loss, 1e-8 * loss) << "nk=" << nk;
    if (best_nk < 0 || loss < best_loss) {
      best_nk = nk;
      best_loss = loss;
    }
  }
  EXPECT_EQ(r.model.nk, best_nk);  // the scan chooses QR's smallest loss
}

TEST(IntegratorDelayModel, RejectsBadInput) {
  const Eigen::VectorXd flat = Eigen::VectorXd::Constant(200, 10.0);
  const Eigen::VectorXd level = Eigen::VectorXd::Constant(200, 2.0);
  EXPECT_THROW(FitIntegratorDelay(flat, flat, level, 60.0),
               std::invalid_argument);  // inflow never moves
  const Eigen::VectorXd q_in = BinaryInflow(200, 10.0, 1.0, 5, 1);
  IntegratorDelayFitOptions options;
  options.max_nk = 190;  // leaves fewer than 20 samples to fit
  EXPECT_THROW(FitIntegratorDelay(q_in, flat, level, 60.0, options), std::invalid_argument);
  EXPECT_THROW(FitIntegratorDelay(q_in, flat.head(10), level, 60.0), std::invalid_argument);
  Eigen::VectorXd with_nan = level;
  with_nan(3) = std::nan("");
  EXPECT_THROW(FitIntegratorDelay(q_in, flat, with_nan, 60.0), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
