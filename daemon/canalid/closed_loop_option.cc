#include "daemon/canalid/closed_loop_option.h"

#include <CLI/CLI.hpp>
#include <optional>

#include "daemon/canalid/input_error.h"

namespace canalid::cli {
namespace {

std::optional<core::ClosedLoopMode> Lookup(const std::string& value) {
  if (value == "auto") return core::ClosedLoopMode::kAuto;
  if (value == "on" || value == "three-step") return core::ClosedLoopMode::kThreeStep;
  if (value == "iv") return core::ClosedLoopMode::kOn;
  if (value == "off") return core::ClosedLoopMode::kOff;
  return std::nullopt;
}

std::string Refusal(const std::string& value) {
  std::string allowed;
  for (const char* v : kClosedLoopValues) allowed += std::string(allowed.empty() ? "" : ", ") + v;
  return "'" + value + "' is not one of " + allowed;
}

}  // namespace

core::ClosedLoopMode ParseClosedLoop(const std::string& value) {
  if (const auto mode = Lookup(value)) return *mode;
  throw InputError("--closed-loop: " + Refusal(value));
}

CLI::Option* AddClosedLoopOption(CLI::App& cmd, std::string& value) {
  return cmd
      .add_option("--closed-loop", value,
                  "auto: decide from the data (outflow moving and following the level); on "
                  "(or three-step): the three-step closed-loop method (--online: recursive, one "
                  "per candidate delay, the delay from the IV bank); iv: --online only, "
                  "instrumental-variable RLS (instrument the integrated delayed inflow); off: "
                  "open-loop fit (--online: RLS).  --online auto runs IV and RLS over the first "
                  "200 samples after the longest delay (all of them if fewer), then keeps the one "
                  "the batch test picks")
      ->check(CLI::Validator([](std::string& v) { return Lookup(v) ? std::string() : Refusal(v); },
                             "auto|on|three-step|iv|off"))
      ->capture_default_str();
}

}  // namespace canalid::cli
