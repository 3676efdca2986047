#pragma once
#include <Eigen/Core>

namespace canalid::core {

/// True when every root of A(z) = 1 + a_1 z^-1 + ... + a_n z^-n lies strictly inside the unit
/// circle (Schur-Cohn step-down test on the reflection coefficients).  An empty `a` is stable.
bool IsStablePolynomial(const Eigen::Ref<const Eigen::VectorXd>& a);

/// What PrefilterInverseA applied.
struct PrefilterResult {
  Eigen::VectorXd filtered;
  Eigen::VectorXd a_polynomial;  ///< [1, a_1, .., a_n]: L(z) = 1 / A(z)
  double dc_gain = 1.0;          ///< L(1) = 1 / sum(a_polynomial)
};

/// Low-pass prefilter L(z) = 1 / A(z) with A from a first ARX fit (docs/references.md):
///   w(t) = x(t) - a_1 w(t-1) - ... - a_n w(t-n),   w(t < 0) = 0.
/// Filter the output and every input with the same L so the input-output relation is kept and
/// the fit moves toward the low frequencies where A_hat has its poles.
/// @param a  a_1..a_n (ArxModel::a); A must be stable (see IsStablePolynomial).
/// @throws std::invalid_argument if a is unstable or not finite, or x is not finite.
PrefilterResult PrefilterInverseA(const Eigen::Ref<const Eigen::VectorXd>& a,
                                  const Eigen::Ref<const Eigen::VectorXd>& x);

}  // namespace canalid::core
