#pragma once
#include <Eigen/Core>

namespace canalid::core {

/// Grunwald-Letnikov weights w_j = (-1)^j binom(alpha, j), j = 0..count-1, by the recursion
///   w_0 = 1,  w_j = w_{j-1} (1 - (alpha + 1) / j).
/// The GL difference of order alpha with step h is D^alpha x(k) ~ h^-alpha sum_j w_j x(k-j).
/// For a non-negative integer alpha the weights vanish exactly for j > alpha.
/// @param alpha any real order (negative orders give fractional sums).
/// @throws std::invalid_argument if count < 1 or alpha is not finite.
Eigen::VectorXd GrunwaldLetnikovWeights(double alpha, int count);

/// Short-memory length L for the GL difference of order alpha > 0: the number of past terms
/// (w_1..w_L) to keep so that the neglected tail sum_{j>L} w_j, whose size is about
///   |L^-alpha / Gamma(1 - alpha)|,
/// is at most `tail_tolerance`.  Because sum_j w_j = 0 for alpha > 0, the tail equals minus the
/// partial sum S(L) = sum_{j=0..L} w_j, which is what a held signal sees: a GL1 simulation of
/// K/(1 + T s^alpha) with step h settles at K / (1 + T h^-alpha S(L)), so pass
/// tail_tolerance = relative_gain_error * h^alpha / T to bound that static error.
/// - Integer alpha (1/Gamma(1-alpha) = 0): the weights end at j = alpha, L = alpha.
/// - 1 < alpha < 2: Gamma(1-alpha) < 0, the tail is smaller than for alpha < 1 and the bound
///   uses its magnitude.
/// The asymptotic bound is checked against the exact partial sum, and L grows until the exact
/// partial sum meets the tolerance (the bound is only asymptotic for small L).
/// The result is clamped to max_length (returned as is when the tolerance cannot be met).
/// @throws std::invalid_argument unless alpha > 0, tail_tolerance > 0 and max_length >= 1.
int GrunwaldLetnikovMemoryLength(double alpha, double tail_tolerance, int max_length = 1 << 24);

/// Exact partial sum S(L) = sum_{j=0..L} w_j = (-1)^L binom(alpha - 1, L), evaluated by the
/// product S(L) = prod_{j=1..L} (1 - alpha / j).
double GrunwaldLetnikovPartialSum(double alpha, int length);

}  // namespace canalid::core
