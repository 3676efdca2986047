#pragma once
#include <cmath>
#include <string_view>

namespace canalid::core {

/// Throws std::invalid_argument "<owner>.<name> = <value> is out of range (allowed: <range>)", the
/// one wording of every online estimator's option check (owner: the options struct, such as
/// "OnlineArxOptions").
[[noreturn]] void ThrowOptionOutOfRange(std::string_view owner, std::string_view name, double value,
                                        std::string_view range);

/// A value an estimator may keep: finite and at most `bound` in magnitude.
inline bool FiniteWithin(double value, double bound) {
  return std::isfinite(value) && std::abs(value) <= bound;
}

}  // namespace canalid::core
