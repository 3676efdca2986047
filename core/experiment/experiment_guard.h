#pragma once
#include <cstdint>
#include <optional>
#include <string>

namespace canalid::core {

/// The record a reach persists before the first excitation write of an experiment and removes
/// once the PLC has confirmed the nominal setpoint back at its end or abort.  Found at start-up,
/// it says an experiment was interrupted (crash, kill, power cut) with the actuator possibly left
/// at a PRBS level, and what the nominal setpoint was.
struct ExperimentGuard {
  std::string reach;
  std::string actuator;               ///< the excited channel's name
  std::string experiment;             ///< the experiment's name
  double nominal_setpoint = 0.0;      ///< the actuator's nominal, its engineering unit
  std::int64_t started_utime_us = 0;  ///< when the guard was written, us since the Unix epoch
};

/// What the state directory held for a reach at start-up.
struct GuardReading {
  enum class Kind : std::uint8_t {
    kNone,     ///< no guard: the last experiment ended with its nominal confirmed
    kFound,    ///< a readable guard (in `guard`)
    kCorrupt,  ///< a guard file that cannot be read, parsed or trusted (why in `problem`)
  };
  Kind kind = Kind::kNone;
  ExperimentGuard guard;
  std::string problem;  ///< "PATH: reason" for kCorrupt
};

/// What the reach is at start-up, from the configuration.
struct RestartContext {
  std::string reach;
  std::string actuator;  ///< the reach's actuator channel
  double setpoint_min = 0.0;
  double setpoint_max = 0.0;
  std::optional<double> configured_nominal;  ///< reach.nominal_setpoint
};

/// What a reach does first on a start that may follow an interrupted experiment.
struct RestartDecision {
  enum class Action : std::uint8_t {
    kNone,     ///< no interrupted experiment: start as usual
    kRestore,  ///< write restore_setpoint first; no experiment until the PLC confirms it
    kRefuse,   ///< no excitation in this run (an operator must look); restore if it can
  };
  Action action = Action::kNone;
  /// Written to the actuator before anything else, held until the PLC confirms it.
  std::optional<double> restore_setpoint;
  /// The reach's nominal setpoint; none: its first reading (kNone) or unknown (kRefuse: the
  /// reading may be a PRBS level and is not taken).
  std::optional<double> nominal;
  bool excitation_allowed = true;    ///< false: no experiment starts in this run
  bool hold_until_restored = false;  ///< no experiment before restore_setpoint is confirmed
  bool error = false;                ///< log `message` as an error (else as a warning)
  std::string message;               ///< for the log: names the reach, the values and the time
};

/// The start-up rules, in this order:
///   no guard -> as usual (configured nominal, or the first reading);
///   corrupt guard, or one naming another reach -> interrupted with an unknown nominal: no
///     excitation, an error; the configured nominal (when there is one) is restored and adopted;
///   a guard for an actuator the reach no longer has -> no excitation, an error, no write (that
///     actuator is not ours to write);
///   a guard whose nominal is not finite or lies outside [setpoint_min, setpoint_max] -> as
///   corrupt; otherwise -> restore the guard's nominal first, hold experiments until it is
///   confirmed, and
///     adopt it as the nominal unless one is configured (the configured one wins for experiments;
///     the message says when the two differ).
/// Pure.
RestartDecision DecideRestart(const RestartContext& context, const GuardReading& reading);

/// `utime_us` as "YYYY-MM-DDTHH:MM:SSZ" (UTC), for log lines.
std::string FormatUtcTime(std::int64_t utime_us);

/// The reasons of the experiment state message a daemon publishes at start-up for an interrupted
/// experiment (docs/lcm-channels.md): the setpoint field holds the restored value (NaN: none).
inline constexpr const char* kRestartRestoreReason = "interrupted experiment: restoring nominal";
inline constexpr const char* kRestartRefusedReason = "interrupted experiment: excitation refused";

/// The decision a published start-up message stands for (`canalid replay` applies it to its
/// reach as the daemon did); none when `reason` is not one of the two above.
std::optional<RestartDecision> RestartDecisionFromMessage(const std::string& reason,
                                                          double setpoint,
                                                          std::optional<double> configured_nominal);

}  // namespace canalid::core
