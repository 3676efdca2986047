#pragma once

namespace canalid::core {

/// One-parameter Mittag-Leffler function E_alpha(z) = sum_{k>=0} z^k / Gamma(alpha k + 1) for
/// real z <= 0 and 0 < alpha < 2 (E_1(z) = exp(z), E_{1/2}(z) = exp(z^2) erfc(-z)).
/// Method, with t = (-z)^(1/alpha):
/// - t <= 15: the power series in long double (the largest term is about e^t, so cancellation
///   costs at most ~1e-13 of the 1e-19 long-double precision);
/// - t > 15: the Laplace-inversion representation (Hankel contour collapsed on the branch cut)
///     E_alpha(-t^alpha) = int_0^inf e^{-r t} K_alpha(r) dr  [+ (2/alpha) e^{t cos(pi/alpha)}
///                                                             cos(t sin(pi/alpha)) if alpha > 1],
///     K_alpha(r) = sin(alpha pi) r^(alpha-1) / (pi (r^(2 alpha) + 2 r^alpha cos(alpha pi) + 1)),
///   integrated by the trapezoidal rule after r = s / t, s = exp((pi/2) sinh v) (double-
///   exponential decay at both ends), with a step in [2e-4, 0.02] that resolves the peak of
///   K_alpha at r = 1 when alpha is near 1.
/// Absolute accuracy about 1e-12 (1e-10 guaranteed by the tests) for |alpha - 1| >= 1e-3; alpha
/// exactly 1 returns exp(z).
/// @throws std::invalid_argument unless 0 < alpha < 2 and z <= 0 (finite).
double MittagLeffler(double alpha, double z);

}  // namespace canalid::core
