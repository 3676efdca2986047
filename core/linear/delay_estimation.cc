#include "core/linear/delay_estimation.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/linear/correlation.h"

namespace canalid::core {
namespace {

std::string Str(Eigen::Index v) { return std::to_string(v); }

}  // namespace

void ArxDelayScanOptions::Validate(Eigen::Index num_inputs) const {
  if (input < 0 || input >= num_inputs) {
    throw std::invalid_argument("ArxDelayScanOptions.input = " + Str(input) + " must be in [0, " +
                                Str(num_inputs - 1) + "]");
  }
  orders.Validate(num_inputs);
  if (orders.nb[static_cast<std::size_t>(input)] < 1) {
    throw std::invalid_argument("ArxDelayScanOptions.orders.nb[" + Str(input) +
                                "] = " + Str(orders.nb[static_cast<std::size_t>(input)]) +
                                " must be >= 1 for the scanned input");
  }
  if (min_nk < 0 || max_nk < min_nk) {
    throw std::invalid_argument("ArxDelayScanOptions: min_nk = " + Str(min_nk) +
                                ", max_nk = " + Str(max_nk) + "; need 0 <= min_nk <= max_nk");
  }
}

ArxDelayScan ScanArxDelay(const Eigen::Ref<const Eigen::VectorXd>& y,
                          const Eigen::Ref<const Eigen::MatrixXd>& u,
                          const ArxDelayScanOptions& options) {
  options.Validate(u.cols());
  if (u.rows() != y.size()) {
    throw std::invalid_argument("ScanArxDelay: u has " + Str(u.rows()) + " rows, y has " +
                                Str(y.size()) + " samples; they must be equal");
  }
  if (!y.allFinite() || !u.allFinite()) {
    throw std::invalid_argument("ScanArxDelay: y or u contains a NaN or infinite value");
  }
  const auto scanned = static_cast<std::size_t>(options.input);
  const int nb = options.orders.nb[scanned];

  // The fixed part: output lags and the other inputs, in FitArx's column order minus the scanned
  // input.  The window must suit the longest candidate delay.
  ArxOrders fixed = options.orders;
  fixed.nb[scanned] = 0;
  ArxOrders longest = options.orders;
  longest.nk[scanned] = options.max_nk;
  const Eigen::Index t0 = longest.min_first_sample();
  const Eigen::Index n = y.size() - t0;
  const int f = fixed.num_parameters();
  if (n <= f + nb) {
    throw std::invalid_argument(
        "ScanArxDelay: " + Str(std::max<Eigen::Index>(n, 0)) + " equations for " + Str(f + nb) +
        " parameters at max_nk = " + Str(options.max_nk) + "; need a longer record");
  }

  Eigen::HouseholderQR<Eigen::MatrixXd> fixed_qr;
  Eigen::Index rows = n;
  if (f > 0) {
    const Eigen::MatrixXd phi_fixed = ArxRegressors(y, u, fixed, t0);
    fixed_qr.compute(phi_fixed);
    // Rank check on R's diagonal relative to the column norms (no pivoting here, for speed).
    const Eigen::VectorXd diag = fixed_qr.matrixQR().diagonal().cwiseAbs();
    for (int j = 0; j < f; ++j) {
      if (!(diag(j) > 1e-12 * phi_fixed.col(j).norm())) {
        throw std::invalid_argument(
            "ScanArxDelay: the output lags and fixed inputs are rank deficient (column " + Str(j) +
            "): not persistently exciting for these orders");
      }
    }
    rows = n - f;  // the components orthogonal to the fixed columns
  }

  ArxDelayScan scan;
  scan.first_sample = t0;
  scan.num_samples = n;
  const int candidates = options.max_nk - options.min_nk + 1;
  scan.loss.resize(candidates);
  scan.leading_b_t.resize(candidates);
  scan.nk.reserve(static_cast<std::size_t>(candidates));
  const double dof = static_cast<double>(n - f - nb);
  // The candidates in blocks of kScanBlock: per block the columns u(t - L) for its lags L, then
  // y(t), projected off the fixed columns; the memory is N x (kScanBlock + nb) whatever the
  // number of candidates (all at once took N x (K + nb): 115 MB for 12 000 samples and 1 200
  // delays).
  constexpr int kScanBlock = 64;
  Eigen::MatrixXd z;
  Eigen::MatrixXd block(rows, nb + 1);
  for (int first_nk = options.min_nk; first_nk <= options.max_nk; first_nk += kScanBlock) {
    const int count = std::min(kScanBlock, options.max_nk - first_nk + 1);
    const int lags = count + nb - 1;
    z.resize(n, lags + 1);  // allocates only when the width changes (the last block)
    for (int l = 0; l < lags; ++l) z.col(l) = u.col(options.input).segment(t0 - first_nk - l, n);
    z.col(lags) = y.segment(t0, n);
    if (f > 0) z.applyOnTheLeft(fixed_qr.householderQ().adjoint());
    const auto projected = z.bottomRows(rows);
    for (int c = 0; c < count; ++c) {
      const int nk = first_nk + c;
      const int i = nk - options.min_nk;
      block.leftCols(nb) = projected.middleCols(c, nb);
      block.col(nb) = projected.col(lags);
      const Eigen::VectorXd norms = block.leftCols(nb).colwise().norm().transpose();
      // QR of [U_block, y]: the last diagonal entry of R is the residual norm (Octave's
      // "square-root" form), so no solve is needed for the loss.
      Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(block);
      const double residual = qr.matrixQR()(nb, nb);
      for (int j = 0; j < nb; ++j) {
        if (!(std::abs(qr.matrixQR()(j, j)) > 1e-12 * norms(j))) {
          throw std::invalid_argument("ScanArxDelay: the scanned input is rank deficient at nk = " +
                                      Str(nk) + " (constant or collinear with the fixed part)");
        }
      }
      scan.nk.push_back(nk);
      scan.loss(i) = residual * residual / static_cast<double>(n);
      // [R11 r12; 0 r22]: theta = R11^-1 r12, cov = sigma^2 R11^-1 R11^-T (Frisch-Waugh: the
      // same as in the full fit).
      const auto r11 = qr.matrixQR().topLeftCorner(nb, nb).triangularView<Eigen::Upper>();
      const Eigen::VectorXd theta = r11.solve(qr.matrixQR().col(nb).head(nb));
      const Eigen::MatrixXd r11_inv = r11.solve(Eigen::MatrixXd::Identity(nb, nb));
      const double sigma = std::abs(residual) / std::sqrt(dof);
      const double std0 = sigma * r11_inv.row(0).norm();
      scan.leading_b_t(i) = std0 > 0.0 ? theta(0) / std0 : 0.0;
    }
  }
  Eigen::Index best = 0;
  scan.loss.minCoeff(&best);
  scan.best_nk = scan.nk[static_cast<std::size_t>(best)];
  constexpr double kSignificant = 2.576;  // two-sided 99 % normal quantile
  Eigen::Index refined = best;
  while (refined + 1 < scan.loss.size() && std::abs(scan.leading_b_t(refined)) < kSignificant) {
    ++refined;
  }
  scan.refined_nk = scan.nk[static_cast<std::size_t>(refined)];
  return scan;
}

void CorrelationDelayOptions::Validate() const {
  if (ar_order < 1) {
    throw std::invalid_argument("CorrelationDelayOptions.ar_order = " + Str(ar_order) +
                                " must be >= 1");
  }
  if (max_lag < 0) {
    throw std::invalid_argument("CorrelationDelayOptions.max_lag = " + Str(max_lag) +
                                " must be >= 0");
  }
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("CorrelationDelayOptions.confidence = " +
                                std::to_string(confidence) + " must be in (0, 1)");
  }
}

CorrelationDelayEstimate EstimateDelayByCorrelation(const Eigen::Ref<const Eigen::VectorXd>& y,
                                                    const Eigen::Ref<const Eigen::VectorXd>& u,
                                                    const CorrelationDelayOptions& options) {
  options.Validate();
  if (y.size() != u.size()) {
    throw std::invalid_argument("EstimateDelayByCorrelation: y has " + Str(y.size()) +
                                " samples, u " + Str(u.size()) + "; they must be equal");
  }
  if (u.size() < 2 * options.ar_order + options.max_lag + 2) {
    throw std::invalid_argument("EstimateDelayByCorrelation: " + Str(u.size()) +
                                " samples are too few for ar_order " + Str(options.ar_order) +
                                " and max_lag " + Str(options.max_lag));
  }
  CorrelationDelayEstimate estimate;
  const Eigen::VectorXd c = FitAr(u, options.ar_order);
  estimate.whitening_a.resize(c.size() + 1);
  estimate.whitening_a << 1.0, c;
  const Eigen::VectorXd u_white = ApplyPolynomialFilter(c, u);
  const Eigen::VectorXd y_white = ApplyPolynomialFilter(c, y);
  estimate.num_samples = u_white.size();
  estimate.correlation = CrossCorrelation(u_white, y_white, options.max_lag);
  estimate.bound = TwoSidedNormalQuantile(options.confidence) /
                   std::sqrt(static_cast<double>(estimate.num_samples));
  Eigen::Index peak = 0;
  estimate.correlation.cwiseAbs().maxCoeff(&peak);
  estimate.peak_lag = static_cast<int>(peak);
  estimate.peak_correlation = estimate.correlation(peak);
  for (int k = 0; k <= options.max_lag; ++k) {
    if (std::abs(estimate.correlation(k)) > estimate.bound) {
      estimate.first_significant_lag = k;
      break;
    }
  }
  return estimate;
}

}  // namespace canalid::core
