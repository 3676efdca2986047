#pragma once
#include <Eigen/Core>

namespace canalid::core {

/// Least-squares AR model of a series, x(t) + c_1 x(t-1) + ... + c_n x(t-n) = e(t), over
/// t = n..N-1 (FitArx's problem with no input), by a QR folded a block of rows at a time, so that
/// its memory does not grow with N.  Returns c_1..c_n.
/// @throws std::invalid_argument if order < 1, the series has <= 2 * order samples, or the
///         regressor is rank deficient (e.g. a constant series).
Eigen::VectorXd FitAr(const Eigen::Ref<const Eigen::VectorXd>& x, int order);

/// Moving-average filter with the polynomial C(q) = 1 + c_1 q^-1 + ... + c_n q^-n:
///   w(t) = x(t) + c_1 x(t-1) + ... + c_n x(t-n), for t = n..N-1 only (the first n samples,
/// which would need values before time 0, are dropped: the result has N - n samples).
/// With c from FitAr this is the prewhitening filter of x.
/// @throws std::invalid_argument if x has fewer than n + 1 samples.
Eigen::VectorXd ApplyPolynomialFilter(const Eigen::Ref<const Eigen::VectorXd>& c,
                                      const Eigen::Ref<const Eigen::VectorXd>& x);

/// Normalised cross-correlation for lags k = 0..max_lag:
///   r(k) = sum_{t=0}^{N-1-k} (x(t) - mean x)(y(t+k) - mean y) / (N sd_x sd_y),
/// sd the root mean square of the centred series (the biased estimator, as in Box-Jenkins and
/// MATLAB's crosscorr).  When x is white and independent of y, r(k) ~ N(0, 1/N) approximately.
/// @throws std::invalid_argument if sizes differ, max_lag < 0 or >= N, or a series is constant.
Eigen::VectorXd CrossCorrelation(const Eigen::Ref<const Eigen::VectorXd>& x,
                                 const Eigen::Ref<const Eigen::VectorXd>& y, int max_lag);

/// z with P(|Z| <= z) = confidence for a standard normal Z (two-sided): 0.95 -> 1.960,
/// 0.99 -> 2.576.  Solved by bisection on erfc.
/// @throws std::invalid_argument unless 0 < confidence < 1.
double TwoSidedNormalQuantile(double confidence);

}  // namespace canalid::core
