#include "core/fractional/grunwald_letnikov.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace canalid::core {

Eigen::VectorXd GrunwaldLetnikovWeights(double alpha, int count) {
  if (count < 1) {
    throw std::invalid_argument("GrunwaldLetnikovWeights: count = " + std::to_string(count) +
                                " must be >= 1");
  }
  if (!std::isfinite(alpha)) {
    throw std::invalid_argument("GrunwaldLetnikovWeights: alpha must be finite");
  }
  Eigen::VectorXd w(count);
  w(0) = 1.0;
  for (int j = 1; j < count; ++j) {
    w(j) = w(j - 1) * (1.0 - (alpha + 1.0) / j);
  }
  return w;
}

double GrunwaldLetnikovPartialSum(double alpha, int length) {
  // sum_{j<=L} (-1)^j binom(alpha, j) = (-1)^L binom(alpha - 1, L) = prod_{j=1..L} (1 - alpha/j).
  double s = 1.0;
  for (int j = 1; j <= length; ++j) {
    s *= 1.0 - alpha / j;
  }
  return s;
}

int GrunwaldLetnikovMemoryLength(double alpha, double tail_tolerance, int max_length) {
  if (!(alpha > 0.0) || !std::isfinite(alpha)) {
    throw std::invalid_argument("GrunwaldLetnikovMemoryLength: alpha = " + std::to_string(alpha) +
                                " must be > 0");
  }
  if (!(tail_tolerance > 0.0)) {
    throw std::invalid_argument("GrunwaldLetnikovMemoryLength: tail_tolerance = " +
                                std::to_string(tail_tolerance) + " must be > 0");
  }
  if (max_length < 1) {
    throw std::invalid_argument("GrunwaldLetnikovMemoryLength: max_length = " +
                                std::to_string(max_length) + " must be >= 1");
  }
  const double rounded = std::round(alpha);
  if (std::abs(alpha - rounded) < 1e-12) {
    return std::min(max_length, static_cast<int>(rounded));
  }
  // Start from the asymptotic bound L^-alpha / |Gamma(1-alpha)| <= tol, then walk in doubling
  // steps on the exact partial sum (cheap: one product per term) to absorb the small-L error.
  const double inv_gamma = 1.0 / std::abs(std::tgamma(1.0 - alpha));
  const double guess = std::pow(tail_tolerance / inv_gamma, -1.0 / alpha);
  int length = guess >= max_length ? max_length : std::max(1, static_cast<int>(std::ceil(guess)));
  double s = GrunwaldLetnikovPartialSum(alpha, length);
  while (std::abs(s) > tail_tolerance && length < max_length) {
    const int next = length >= max_length / 2 ? max_length : 2 * length;
    for (int j = length + 1; j <= next; ++j) {
      s *= 1.0 - alpha / j;
    }
    length = next;
  }
  return length;
}

}  // namespace canalid::core
