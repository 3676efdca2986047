#pragma once
#include <string>

#include "core/integrator_delay/integrator_delay_model.h"

namespace CLI {
class App;
class Option;
}  // namespace CLI

namespace canalid::cli {

/// The one meaning of `--closed-loop` for every command that takes it (identify, identify
/// --online, report), the same as the daemon's `closed_loop` key:
///   auto        decide from the data (the outflow moves and follows the level);
///   on          the three-step closed-loop method (Van den Hof and Schrama); three-step is the
///               same value under its own name;
///   iv          --online only: the instrumental-variable RLS bank on the plain regression;
///   off         the open-loop fit (least squares).
/// @throws InputError naming the value and the allowed ones.
core::ClosedLoopMode ParseClosedLoop(const std::string& value);

/// The accepted values, in the order the help lists them.
inline constexpr const char* kClosedLoopValues[] = {"auto", "on", "three-step", "iv", "off"};

/// Registers `--closed-loop` on `cmd` (a command or an option group), checked by ParseClosedLoop.
CLI::Option* AddClosedLoopOption(CLI::App& cmd, std::string& value);

}  // namespace canalid::cli
