#pragma once
#include <cmath>
#include <limits>

namespace canalid::core {

/// The equilibrium a process model's deviations are taken from: the first sample whose input and
/// output are both finite.  The online process estimators (ARX, fractional, LPV) have no offset
/// term and assume signals that start from rest, so they see u - u0 and y - y0.  Until the first
/// such sample both deviations are NaN (the estimators count them as bad).
class OperatingPoint final {
 public:
  /// Takes the sample as the equilibrium if none is known yet and it is usable.
  void Observe(double input, double output) {
    if (known_ || !std::isfinite(input) || !std::isfinite(output)) return;
    input_ = input;
    output_ = output;
    known_ = true;
  }
  double InputDeviation(double input) const { return known_ ? input - input_ : kNan; }
  double OutputDeviation(double output) const { return known_ ? output - output_ : kNan; }
  bool known() const { return known_; }
  double input() const { return known_ ? input_ : kNan; }
  double output() const { return known_ ? output_ : kNan; }
  void Reset() { known_ = false; }

 private:
  static constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  bool known_ = false;
  double input_ = 0.0;
  double output_ = 0.0;
};

}  // namespace canalid::core
