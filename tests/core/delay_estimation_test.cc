#include "core/linear/delay_estimation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>

#include "core/linear/arx_delay_scan.h"
#include "core/signal/prbs.h"

namespace canalid::core {
namespace {

// A pool-like plant written out independently: inflow u1 through a delay of `nk` samples and a
// slow second-order response, outflow u2 with nk = 1, equation noise:
//   y(t) - 1.6 y(t-1) + 0.64 y(t-2) = 0.05 u1(t-nk) + 0.03 u1(t-nk-1) - 0.04 u2(t-1) + e(t)
struct Record {
  Eigen::VectorXd y;
  Eigen::MatrixXd u;
};

Record MakeRecord(int n, int nk, double noise_std, unsigned seed) {
  PrbsSignalSpec spec;
  spec.amplitude = 1.0;
  spec.clock_period_samples = 6;
  spec.order = 10;
  const Eigen::VectorXd prbs = GeneratePrbs(spec, n);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Record r{Eigen::VectorXd::Zero(n), Eigen::MatrixXd::Zero(n, 2)};
  r.u.col(0) = prbs;
  for (int t = 0; t < n; ++t) r.u(t, 1) = normal(rng);
  auto y = [&](int t) { return t >= 0 ? r.y(t) : 0.0; };
  auto u = [&](int t, int i) { return t >= 0 ? r.u(t, i) : 0.0; };
  for (int t = 0; t < n; ++t) {
    r.y(t) = 1.6 * y(t - 1) - 0.64 * y(t - 2) + 0.05 * u(t - nk, 0) + 0.03 * u(t - nk - 1, 0) -
             0.04 * u(t - 1, 1) + noise_std * normal(rng);
  }
  return r;
}

ArxDelayScanOptions TwoInputScan(int min_nk, int max_nk) {
  ArxDelayScanOptions o;
  o.orders.na = 2;
  o.orders.nb = {2, 1};
  o.orders.nk = {0, 1};
  o.input = 0;
  o.min_nk = min_nk;
  o.max_nk = max_nk;
  return o;
}

TEST(DelayEstimation, ScanFindsTheTrueDelayAndTheLossIsMinimalThere) {
  const Record r = MakeRecord(4000, 17, 0.01, 1);
  const ArxDelayScan scan = ScanArxDelay(r.y, r.u, TwoInputScan(0, 40));
  EXPECT_EQ(scan.best_nk, 17);
  ASSERT_EQ(scan.nk.size(), 41U);
  EXPECT_EQ(scan.nk.front(), 0);
  EXPECT_EQ(scan.nk.back(), 40);
  // The minimum is sharp: every other candidate loses at least 20 % (the true model explains the
  // PRBS response, a shifted one cannot).  At the truth V is the noise variance 1e-4 within 10 %.
  for (std::size_t i = 0; i < scan.nk.size(); ++i) {
    if (scan.nk[i] != 17) {
      EXPECT_GT(scan.loss(static_cast<Eigen::Index>(i)), 1.2 * scan.loss(17)) << "nk " << i;
    }
  }
  EXPECT_NEAR(scan.loss(17), 1e-4, 1e-5);
  // Common window: max(na, nb + max_nk - 1, nb2 + nk2 - 1) = 41.
  EXPECT_EQ(scan.first_sample, 41);
  EXPECT_EQ(scan.num_samples, 4000 - 41);
}

TEST(DelayEstimation, ScanInBlocksEqualsFullFitsAcrossBlockEdges) {
  // 150 candidates go in blocks of 64: 3..66, 67..130, 131..152 (the last one partial).  Every
  // loss, and the leading coefficient's t value, still equal the full fit's at that delay.
  const Record r = MakeRecord(2500, 100, 0.05, 5);
  const ArxDelayScanOptions options = TwoInputScan(3, 152);
  const ArxDelayScan scan = ScanArxDelay(r.y, r.u, options);
  ASSERT_EQ(scan.nk.size(), 150U);
  EXPECT_EQ(scan.best_nk, 100);
  for (std::size_t i = 0; i < scan.nk.size(); ++i) {
    ASSERT_EQ(scan.nk[i], static_cast<int>(i) + 3);
    ArxOrders orders = options.orders;
    orders.nk[0] = scan.nk[i];
    const ArxModel m = FitArx(r.y, r.u, orders, scan.first_sample);
    EXPECT_NEAR(scan.loss(static_cast<Eigen::Index>(i)), m.loss, 1e-10 * m.loss)
        << "nk " << scan.nk[i];
    const double t = m.b[0](0) / std::sqrt(m.covariance(2, 2));
    EXPECT_NEAR(scan.leading_b_t(static_cast<Eigen::Index>(i)), t, 1e-8 * std::abs(t) + 1e-10)
        << "nk " << scan.nk[i];
  }
}

TEST(DelayEstimation, ArxOverDelaysIsTheFullFitOfLeastLoss) {
  // The daemon's batch arx: the delay from the scan, the model from FitArx at it; the same as
  // fitting every candidate in full and keeping the least loss (what it did before the scan).
  const Record r = MakeRecord(3000, 70, 0.02, 6);
  const Eigen::VectorXd u = r.u.col(0);
  const ArxModel fit = FitArxOverDelays(r.y, u, 2, 2, 1, 130);
  ArxOrders widest;
  widest.na = 2;
  widest.nb = {2};
  widest.nk = {130};
  std::optional<ArxModel> best;
  for (int nk = 1; nk <= 130; ++nk) {
    ArxOrders orders = widest;
    orders.nk = {nk};
    ArxModel m = FitArx(r.y, u, orders, widest.min_first_sample());
    if (!best || m.loss < best->loss) best = std::move(m);
  }
  EXPECT_EQ(fit.orders.nk[0], best->orders.nk[0]);
  EXPECT_EQ(fit.orders.nk[0], 70);
  EXPECT_EQ(fit.parameters, best->parameters);
  EXPECT_EQ(fit.loss, best->loss);
  // A constant input has no delay to find: refused with the scan's reason.
  EXPECT_THROW(FitArxOverDelays(r.y, Eigen::VectorXd::Ones(3000), 2, 2, 1, 130),
               std::invalid_argument);
}

TEST(DelayEstimation, EveryScanLossEqualsAFullArxFitOnTheSameWindow) {
  // The Frisch-Waugh shortcut must give exactly the loss of the full least-squares fit.
  const Record r = MakeRecord(1500, 9, 0.05, 2);
  const ArxDelayScanOptions options = TwoInputScan(3, 25);
  const ArxDelayScan scan = ScanArxDelay(r.y, r.u, options);
  for (std::size_t i = 0; i < scan.nk.size(); ++i) {
    ArxOrders orders = options.orders;
    orders.nk[0] = scan.nk[i];
    const ArxModel m = FitArx(r.y, r.u, orders, scan.first_sample);
    EXPECT_NEAR(scan.loss(static_cast<Eigen::Index>(i)), m.loss, 1e-10 * m.loss)
        << "nk " << scan.nk[i];
  }
  EXPECT_EQ(scan.best_nk, 9);
}

TEST(DelayEstimation, SingleInputDefaultAndFourthOrder) {
  const Record r = MakeRecord(3000, 5, 0.01, 3);
  ArxDelayScanOptions o;  // na = nb = 2, input 0 only
  const Eigen::MatrixXd inflow = r.u.leftCols(1);
  // Without the outflow input the model is wrong, but the delay is still the best candidate.
  EXPECT_EQ(ScanArxDelay(r.y, inflow, o).best_nk, 5);
  const ArxDelayScan second = ScanArxDelay(r.y, inflow, o);
  EXPECT_EQ(second.refined_nk, 5);  // b_1 at nk = 5 is significant
  // 4th order: with nb = 4 the candidates nk = 3 and 4 also contain the true lags 5 and 6 (plus
  // earlier useless ones that fit noise), so the loss alone may pick them: the scan's answer is
  // in [3, 5], the loss at the truth is within 1 % of the minimum, and the refinement that steps
  // over insignificant leading coefficients lands on 5.
  o.orders = ArxOrders{4, {4}, {0}};
  const ArxDelayScan fourth = ScanArxDelay(r.y, inflow, o);
  EXPECT_GE(fourth.best_nk, 3);
  EXPECT_LE(fourth.best_nk, 5);
  EXPECT_LE(fourth.loss(5), 1.01 * fourth.loss.minCoeff());
  EXPECT_LT(std::abs(fourth.leading_b_t(3)), 2.576);
  EXPECT_LT(std::abs(fourth.leading_b_t(4)), 2.576);
  EXPECT_GT(std::abs(fourth.leading_b_t(5)), 10.0);
  EXPECT_EQ(fourth.refined_nk, 5);
}

TEST(DelayEstimation, LeadingCoefficientTRatioMatchesTheFullFit) {
  const Record r = MakeRecord(1500, 9, 0.05, 7);
  const ArxDelayScanOptions options = TwoInputScan(0, 15);
  const ArxDelayScan scan = ScanArxDelay(r.y, r.u, options);
  for (int nk : {0, 9, 15}) {
    ArxOrders orders = options.orders;
    orders.nk[0] = nk;
    const ArxModel m = FitArx(r.y, r.u, orders, scan.first_sample);
    const double t = m.parameters(2) / m.parameter_std(2);  // [a1 a2 | b1 b2 | c1]
    EXPECT_NEAR(scan.leading_b_t(nk), t, 1e-8 * std::abs(t) + 1e-10) << "nk " << nk;
  }
  EXPECT_EQ(scan.refined_nk, 9);
}

TEST(DelayEstimation, CorrelationFindsTheDelayWithAColouredInput) {
  // Coloured input: u = white noise through 1 / (1 - 0.9 q^-1), so raw cross-correlation is
  // smeared over many lags.  Plant: y(t) = 0.8 y(t-1) + 0.5 u(t-12) + noise.  Prewhitening makes
  // r(k) proportional to the impulse response 0.5 * 0.8^(k-12) for k >= 12 and ~0 before.
  std::mt19937_64 rng(4);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int n = 5000;
  Eigen::VectorXd u = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd y = Eigen::VectorXd::Zero(n);
  for (int t = 1; t < n; ++t) u(t) = 0.9 * u(t - 1) + normal(rng);
  for (int t = 12; t < n; ++t) y(t) = 0.8 * y(t - 1) + 0.5 * u(t - 12) + 0.5 * normal(rng);
  CorrelationDelayOptions options;
  options.max_lag = 40;
  const CorrelationDelayEstimate c = EstimateDelayByCorrelation(y, u, options);
  EXPECT_EQ(c.first_significant_lag, 12);
  EXPECT_EQ(c.peak_lag, 12);
  EXPECT_GT(c.peak_correlation, 0.0);
  EXPECT_NEAR(c.bound, 2.5758293 / std::sqrt(static_cast<double>(n - 10)), 1e-9);
  EXPECT_EQ(c.num_samples, n - 10);
  ASSERT_EQ(c.whitening_a.size(), 11);
  EXPECT_NEAR(c.whitening_a(1), -0.9, 0.05);  // the AR(10) fit finds the AR(1) colouring
  // Before the delay there is only chance correlation: each of the 12 lags exceeds the 99 % bound
  // with probability 1 %, so two or more would happen with probability ~0.6 %.
  int chance = 0;
  for (int k = 0; k < 12; ++k) chance += std::abs(c.correlation(k)) > c.bound ? 1 : 0;
  EXPECT_LE(chance, 1);
  // Ratio of successive correlations after the delay follows the plant pole 0.8.
  EXPECT_NEAR(c.correlation(13) / c.correlation(12), 0.8, 0.1);
}

TEST(DelayEstimation, CorrelationAndScanAgreeOnThePoolRecord) {
  const Record r = MakeRecord(6000, 23, 0.01, 5);
  CorrelationDelayOptions options;
  options.max_lag = 60;
  const CorrelationDelayEstimate c = EstimateDelayByCorrelation(r.y, r.u.col(0), options);
  EXPECT_EQ(c.first_significant_lag, 23);
  EXPECT_EQ(ScanArxDelay(r.y, r.u, TwoInputScan(0, 60)).best_nk, 23);
}

TEST(DelayEstimation, IntegratorDelayPool) {
  // ID model (docs/references.md): y(k) - y(k-1) = b (q_in(k-nk) - q_out(k-1)), b = Ts/A with
  // Ts = 60 s and A = 5000 m2, PRBS inflow of +-0.1 m3/s (clock 8 samples: +-1.2 mm per sample),
  // random outflow changes, 1 mm level noise, nk = 14.  (With A = 20000 m2 and 3 mm noise the
  // per-sample signal is 0.07 of the noise on the increments and neither method is reliable on
  // 3000 samples.)
  const int n = 3000;
  const int nk = 14;
  const double b = 60.0 / 5000.0;
  PrbsSignalSpec spec;
  spec.nominal = 0.0;
  spec.amplitude = 0.1;
  spec.clock_period_samples = 8;
  spec.order = 9;
  const Eigen::VectorXd q_in = GeneratePrbs(spec, n);
  std::mt19937_64 rng(8);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd q_out = Eigen::VectorXd::Zero(n);
  for (int k = 1; k < n; ++k) q_out(k) = 0.95 * q_out(k - 1) + 0.01 * normal(rng);
  Eigen::VectorXd level = Eigen::VectorXd::Zero(n);
  for (int k = 1; k < n; ++k) {
    level(k) = level(k - 1) + b * ((k >= nk ? q_in(k - nk) : 0.0) - q_out(k - 1));
  }
  Eigen::VectorXd y = level;
  for (int k = 0; k < n; ++k) y(k) += 0.001 * normal(rng);
  Eigen::MatrixXd u(n, 2);
  u << q_in, q_out;
  EXPECT_EQ(ScanArxDelay(y, u, TwoInputScan(0, 40)).refined_nk, nk);
  // Correlation on the level increments (see the header); dy(j) = y(j+1) - y(j) belongs to time
  // j + 1, so it is paired with q_in from time 1 on.
  const Eigen::VectorXd dy = y.tail(n - 1) - y.head(n - 1);
  CorrelationDelayOptions options;
  options.max_lag = 40;
  const CorrelationDelayEstimate c = EstimateDelayByCorrelation(dy, q_in.tail(n - 1), options);
  EXPECT_EQ(c.first_significant_lag, nk);
  EXPECT_EQ(c.peak_lag, nk);
}

TEST(DelayEstimation, RejectsBadArguments) {
  const Record r = MakeRecord(200, 3, 0.01, 6);
  ArxDelayScanOptions o = TwoInputScan(5, 2);
  EXPECT_THROW(ScanArxDelay(r.y, r.u, o), std::invalid_argument);  // max < min
  o = TwoInputScan(0, 10);
  o.input = 2;
  EXPECT_THROW(ScanArxDelay(r.y, r.u, o), std::invalid_argument);
  o = TwoInputScan(0, 10);
  o.orders.nb[0] = 0;
  EXPECT_THROW(ScanArxDelay(r.y, r.u, o), std::invalid_argument);
  o = TwoInputScan(0, 195);
  EXPECT_THROW(ScanArxDelay(r.y, r.u, o), std::invalid_argument);  // window too short
  o = TwoInputScan(0, 10);
  EXPECT_THROW(ScanArxDelay(r.y.head(100), r.u, o), std::invalid_argument);
  Eigen::MatrixXd dead = r.u;
  dead.col(0).setZero();
  EXPECT_THROW(ScanArxDelay(r.y, dead, o), std::invalid_argument);
  CorrelationDelayOptions c;
  c.confidence = 1.0;
  EXPECT_THROW(EstimateDelayByCorrelation(r.y, r.u.col(0), c), std::invalid_argument);
  c = {};
  c.ar_order = 0;
  EXPECT_THROW(EstimateDelayByCorrelation(r.y, r.u.col(0), c), std::invalid_argument);
  c = {};
  c.max_lag = 190;
  EXPECT_THROW(EstimateDelayByCorrelation(r.y, r.u.col(0), c), std::invalid_argument);
  EXPECT_THROW(EstimateDelayByCorrelation(r.y.head(100), r.u.col(0), {}), std::invalid_argument);
}

}  // namespace
}  // namespace canalid::core
