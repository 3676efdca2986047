#pragma once

namespace canalid::core {

/// Exit status of a program that stopped on an unexpected exception (sysexits.h EX_SOFTWARE).
inline constexpr int kExitInternalError = 70;

/// Runs a program's main body and turns an exception that escaped it (a bug: each program
/// reports expected errors itself) into "PROGRAM: internal error: WHAT" on stderr and exit 70,
/// instead of std::terminate's abort.  Every program's main() is `return GuardedMain(...)`.
int GuardedMain(const char* program, int (*body)(int, char**), int argc, char** argv) noexcept;

}  // namespace canalid::core
