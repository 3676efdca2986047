#include "core/signal/prefilter.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace canalid::core {

bool IsStablePolynomial(const Eigen::Ref<const Eigen::VectorXd>& a) {
  if (!a.allFinite()) return false;
  // Step-down (Levinson backward) recursion: A is stable iff every reflection coefficient,
  // the last coefficient of each monic reduced polynomial, has modulus < 1.
  Eigen::VectorXd c(a.size() + 1);
  c << 1.0, a;
  for (Eigen::Index n = a.size(); n >= 1; --n) {
    const double k = c(n);
    if (!(std::abs(k) < 1.0)) return false;
    Eigen::VectorXd reduced(n);
    for (Eigen::Index j = 0; j < n; ++j) reduced(j) = (c(j) - k * c(n - j)) / (1.0 - k * k);
    c = reduced;
  }
  return true;
}

PrefilterResult PrefilterInverseA(const Eigen::Ref<const Eigen::VectorXd>& a,
                                  const Eigen::Ref<const Eigen::VectorXd>& x) {
  if (!IsStablePolynomial(a)) {
    std::ostringstream message;
    message << "PrefilterInverseA: A(z) = [1 " << a.transpose()
            << "] has a root on or outside the unit circle; 1/A would diverge";
    throw std::invalid_argument(message.str());
  }
  if (!x.allFinite()) {
    throw std::invalid_argument("PrefilterInverseA: the series contains NaN or infinite values");
  }
  PrefilterResult result;
  result.a_polynomial.resize(a.size() + 1);
  result.a_polynomial << 1.0, a;
  result.dc_gain = 1.0 / result.a_polynomial.sum();
  result.filtered.resize(x.size());
  for (Eigen::Index t = 0; t < x.size(); ++t) {
    double w = x(t);
    for (Eigen::Index j = 1; j <= a.size() && j <= t; ++j) w -= a(j - 1) * result.filtered(t - j);
    result.filtered(t) = w;
  }
  return result;
}

}  // namespace canalid::core
