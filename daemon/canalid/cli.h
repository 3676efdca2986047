#pragma once

namespace canalid::cli {

/// Exit codes of the offline tool (sysexits-style where one fits).
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitBadInput = 2;  ///< bad CSV, bad column, bad option value

/// Entry point of `canalid`: parses the sub-command and runs it.  Never throws.
int Run(int argc, char** argv);

}  // namespace canalid::cli
