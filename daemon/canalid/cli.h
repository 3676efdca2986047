#pragma once
#include <limits>

namespace CLI {
class Validator;
}

namespace canalid::cli {

/// Exit codes of the offline tool (sysexits-style where one fits).
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitBadInput = 2;  ///< bad CSV, bad column, bad option value

/// The one check of every real-valued option: a finite number in [lo, hi], or in (lo, hi] with
/// open_low.  CLI::Range and CLI::PositiveNumber let "nan" through (every comparison is false).
/// Used as `->check(FiniteIn(0.0, 10.0))`; the message names the value and the range.
CLI::Validator FiniteIn(double lo, double hi, bool open_low = false);
/// (0, largest double]: a finite number > 0.
CLI::Validator FinitePositive();

/// Entry point of `canalid`: parses the sub-command and runs it.  Never throws.
int Run(int argc, char** argv);

}  // namespace canalid::cli
