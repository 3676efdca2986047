#include "core/experiment/experiment_guard.h"

#include <cmath>
#include <ctime>
#include <sstream>

namespace canalid::core {
namespace {

std::string Number(double value) {
  std::ostringstream s;
  s.precision(9);
  s << value;
  return s.str();
}

// Interrupted with no trustworthy nominal: never excite; restore the configured nominal if any.
RestartDecision Unknown(const RestartContext& c, const std::string& why) {
  RestartDecision d;
  d.action = RestartDecision::Action::kRefuse;
  d.excitation_allowed = false;
  d.error = true;
  d.message = "interrupted experiment on reach " + c.reach + ": " + why + "; no excitation";
  if (c.configured_nominal) {
    d.restore_setpoint = c.configured_nominal;
    d.nominal = c.configured_nominal;
    d.message += ", restoring the configured nominal " + Number(*c.configured_nominal);
  } else {
    d.message += ", nominal unknown (none configured): the actuator is not written";
  }
  d.message += " (check the actuator, then remove the guard file)";
  return d;
}

}  // namespace

std::string FormatUtcTime(std::int64_t utime_us) {
  const auto seconds = static_cast<std::time_t>(utime_us / 1000000);
  std::tm tm{};
  if (gmtime_r(&seconds, &tm) == nullptr) return std::to_string(utime_us) + " us";
  char text[32];
  if (std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm) == 0)
    return std::to_string(utime_us) + " us";
  return text;
}

RestartDecision DecideRestart(const RestartContext& c, const GuardReading& r) {
  RestartDecision d;
  switch (r.kind) {
    case GuardReading::Kind::kNone:
      d.nominal = c.configured_nominal;
      return d;
    case GuardReading::Kind::kCorrupt:
      return Unknown(c, "the guard cannot be trusted (" + r.problem + ")");
    case GuardReading::Kind::kFound:
      break;
  }
  const ExperimentGuard& g = r.guard;
  if (g.reach != c.reach) return Unknown(c, "the guard names reach '" + g.reach + "'");
  if (g.actuator != c.actuator) {
    d.action = RestartDecision::Action::kRefuse;
    d.excitation_allowed = false;
    d.error = true;
    d.nominal = c.configured_nominal;
    d.message = "interrupted experiment on reach " + c.reach + ": actuator " + g.actuator +
                " (nominal " + Number(g.nominal_setpoint) + ", persisted at " +
                FormatUtcTime(g.started_utime_us) + ") is no longer the reach's actuator (" +
                c.actuator + "): it may still be at a PRBS level and is not ours to write; no " +
                "excitation (check that actuator, then remove the guard file)";
    return d;
  }
  if (!std::isfinite(g.nominal_setpoint) || g.nominal_setpoint < c.setpoint_min ||
      g.nominal_setpoint > c.setpoint_max) {
    return Unknown(c, "the persisted nominal " + Number(g.nominal_setpoint) + " of " + c.actuator +
                          " lies outside [" + Number(c.setpoint_min) + ", " +
                          Number(c.setpoint_max) + "]");
  }
  d.action = RestartDecision::Action::kRestore;
  d.restore_setpoint = g.nominal_setpoint;
  d.nominal = c.configured_nominal ? c.configured_nominal : d.restore_setpoint;
  d.hold_until_restored = true;
  d.message = "interrupted experiment on reach " + c.reach + ": restoring nominal " +
              Number(g.nominal_setpoint) + " persisted at " + FormatUtcTime(g.started_utime_us) +
              " (" + c.actuator + ", experiment " + g.experiment + ")";
  if (c.configured_nominal && *c.configured_nominal != g.nominal_setpoint) {
    d.message += "; the configured nominal " + Number(*c.configured_nominal) +
                 " differs and is the nominal of the next experiment";
  }
  return d;
}

std::optional<RestartDecision> RestartDecisionFromMessage(
    const std::string& reason, double setpoint, std::optional<double> configured_nominal) {
  RestartDecision d;
  const std::optional<double> value =
      std::isfinite(setpoint) ? std::optional<double>(setpoint) : std::nullopt;
  if (reason.starts_with(kRestartRestoreReason)) {
    if (!value) return std::nullopt;
    d.action = RestartDecision::Action::kRestore;
    d.restore_setpoint = value;
    d.nominal = configured_nominal ? configured_nominal : value;
    d.hold_until_restored = true;
    return d;
  }
  if (reason.starts_with(kRestartRefusedReason)) {
    d.action = RestartDecision::Action::kRefuse;
    d.restore_setpoint = value;
    d.nominal = value ? value : configured_nominal;
    d.excitation_allowed = false;
    return d;
  }
  return std::nullopt;
}

}  // namespace canalid::core
