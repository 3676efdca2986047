#pragma once
#include <Eigen/Core>
#include <vector>

#include "core/linear/arx.h"

namespace canalid::core {

/// Settings of the ARX delay scan (MATLAB `delayest`, defaults na = nb = 2, nk 0..20): orders of
/// every input as in FitArx; the nk of the scanned input is ignored and replaced by each
/// candidate in [min_nk, max_nk].  Unlike delayest, which searches all inputs' delays jointly,
/// one input is scanned and the others keep their given nk (e.g. the outflow with nk = 1).
struct ArxDelayScanOptions {
  ArxOrders orders{2, {2}, {0}};  ///< default na = 2, nb = 2 (use na = nb = 4 for 4th order)
  int input = 0;                  ///< column of u whose delay is scanned
  int min_nk = 0;
  int max_nk = 20;
  /// @throws std::invalid_argument naming the field, the value and the allowed range.
  void Validate(Eigen::Index num_inputs) const;
};

/// Loss curve of the delay scan; loss(i) and leading_b_t(i) belong to nk(i).
struct ArxDelayScan {
  int best_nk = 0;       ///< argmin of loss (the smallest nk on ties): MATLAB delayest's answer
  std::vector<int> nk;   ///< min_nk..max_nk
  Eigen::VectorXd loss;  ///< V = SSR / N of the ARX fit with that nk
  /// t-ratio b_1 / std(b_1) of the scanned input's leading coefficient in each candidate's fit.
  Eigen::VectorXd leading_b_t;
  /// best_nk moved up while the candidate's leading coefficient is not significant
  /// (|leading_b_t| < 2.576, 99 % two-sided) and nk < max_nk.  With nb larger than the true
  /// number of B coefficients, a candidate nk below the truth also contains the true lags (plus
  /// useless earlier ones that fit noise), so the loss alone cannot rule it out; its leading
  /// coefficient is then ~0, which this refinement detects.  Equal to best_nk when b_1 at best_nk
  /// is significant.  It can overshoot if the true first coefficient is itself below the noise.
  int refined_nk = 0;
  Eigen::Index first_sample = 0;  ///< common first equation for every candidate
  Eigen::Index num_samples = 0;   ///< N, the same for every candidate
};

/// Fits the ARX model for every candidate nk on the same data window (first equation
/// t0 = max over candidates of ArxOrders::min_first_sample, so the losses are comparable) and
/// keeps the nk with the lowest loss.  Each loss equals FitArx(y, u, orders with that nk, t0).loss.
///
/// Speed: the regressor columns that do not depend on nk (the na output lags and the other
/// inputs) are factorised once, Phi_f = Q_f R_f, and Q_f^T is applied once to y and to every
/// lagged copy of the scanned input (lags min_nk .. max_nk + nb - 1).  By the Frisch-Waugh-Lovell
/// theorem each candidate's residual is then the residual of a small least-squares problem in the
/// nb projected input columns, solved by Householder QR.  Cost: one QR of N x f, applications
/// of Q_f^T to N x (K + nb (K / 64 + 1)), and K QRs of N x nb (K candidates), instead of K QRs of
/// N x (f + nb).  The candidates go in blocks of 64: memory N x (64 + nb + 1) doubles, whatever K.
/// @throws std::invalid_argument on bad options or data (as FitArx), or a rank-deficient fixed
///         part.
ArxDelayScan ScanArxDelay(const Eigen::Ref<const Eigen::VectorXd>& y,
                          const Eigen::Ref<const Eigen::MatrixXd>& u,
                          const ArxDelayScanOptions& options = {});

/// Settings of the correlation cross-check.
struct CorrelationDelayOptions {
  int ar_order = 10;         ///< order of the AR model of u used as prewhitening filter, >= 1
  int max_lag = 50;          ///< lags 0..max_lag are examined, >= 0
  double confidence = 0.99;  ///< two-sided level of the significance bound, in (0, 1)
  /// @throws std::invalid_argument naming the field, the value and the allowed range.
  void Validate() const;
};

/// Result of the correlation analysis.
struct CorrelationDelayEstimate {
  int first_significant_lag = -1;  ///< first k with |r(k)| > bound, -1 if none
  int peak_lag = 0;                ///< argmax_k |r(k)|
  double peak_correlation = 0.0;   ///< r(peak_lag) (signed)
  double bound = 0.0;              ///< z(confidence) / sqrt(N)
  Eigen::VectorXd correlation;     ///< r(0..max_lag)
  Eigen::VectorXd whitening_a;     ///< [1, c_1..c_n]: the prewhitening filter C(q)
  Eigen::Index num_samples = 0;    ///< N, samples of the prewhitened series
};

/// Correlation analysis with prewhitening (Ljung, Box-Jenkins): fit an AR model C(q) u = e to the
/// input (FitAr), filter both u and y with C(q) (ApplyPolynomialFilter), and compute the
/// normalised cross-correlation r(k) of the filtered input and output (CrossCorrelation).  With a
/// white filtered input r(k) is proportional to the impulse response g(k) of the plant, so the
/// delay is the first lag where r is significant, i.e. |r(k)| > z(confidence)/sqrt(N).
/// Use detrended data.  For an integrating pool pass the level increments y(t) - y(t-1) as y:
/// the level itself wanders like a random walk and its correlation with the input is diluted
/// (the increments' impulse response is b at lag nk and 0 before).
/// @throws std::invalid_argument on bad options, mismatched sizes or too short a record.
CorrelationDelayEstimate EstimateDelayByCorrelation(const Eigen::Ref<const Eigen::VectorXd>& y,
                                                    const Eigen::Ref<const Eigen::VectorXd>& u,
                                                    const CorrelationDelayOptions& options = {});

}  // namespace canalid::core
