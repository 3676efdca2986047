#pragma once
#include <cstdint>
#include <limits>
#include <optional>
#include <string>

#include "core/signal/prbs.h"

namespace canalid::core {

/// Phases of an identification experiment on one reach.
///   idle -> settling -> exciting -> identifying -> done
///                 \________\____________\________> aborted (any fault, stop, bad sample)
/// done and aborted are final for the experiment; a new Start begins another one.
enum class ExperimentPhase : std::uint8_t {
  kIdle,
  kSettling,
  kExciting,
  kIdentifying,
  kDone,
  kAborted
};

/// Settling or exciting: the experiment owns the actuator.
constexpr bool IsRunning(ExperimentPhase phase) {
  return phase == ExperimentPhase::kSettling || phase == ExperimentPhase::kExciting;
}

/// Why an experiment was aborted (kNone otherwise).
enum class AbortReason : std::uint8_t {
  kNone,
  kLevelOutOfBand,        ///< a level left [level_min_m, level_max_m]
  kSensorInvalid,         ///< too many consecutive invalid or stale level samples
  kLinkLost,              ///< the PLC link dropped
  kWriteFailed,           ///< a setpoint write was refused or failed
  kOperatorStop,          ///< stop command, SIGTERM, config reload
  kIdentificationFailed,  ///< the batch identification found no usable model
  kGuardNotPersisted,     ///< the restart guard could not be written before an excitation write
  kSampleGap,  ///< two samples further apart than max_sample_gap_s (stall, overrun, reconnect)
  /// Another member of its joint experiment aborted, or (the leader) a partner could not start
  /// with it (core/reach/joint_experiments.h).
  kJointStop,
};

const char* ExperimentPhaseName(ExperimentPhase phase);
const char* AbortReasonName(AbortReason reason);

/// The experiment as designed (canalid design rules or explicit settings), in actuator units.
struct ExperimentPlan {
  PrbsSignalSpec
      prbs;  ///< nominal = the actuator's nominal setpoint, amplitude, clock, order, seed
  std::int64_t settle_samples = 0;  ///< samples at nominal before exciting, >= 0
  std::int64_t excite_samples = 1;  ///< samples of excitation, >= 1
  /// > 0: a step experiment instead of the PRBS: nominal + prbs.amplitude for this many samples,
  /// then back to nominal for as many (excite_samples = 2 step_hold_samples); 0: the PRBS.
  std::int64_t step_hold_samples = 0;
  double level_min_m = 0.0;     ///< the band the level must stay in while the actuator moves
  double level_max_m = 0.0;     ///< > level_min_m
  int max_invalid_samples = 0;  ///< consecutive invalid level samples tolerated, >= 0
  /// Largest time between two consecutive samples while settling or exciting (s of the samples'
  /// clock, > 0; infinity: not checked).  A longer gap, or time going back, means the record is
  /// not uniformly sampled: the experiment aborts (kSampleGap).
  double max_sample_gap_s = std::numeric_limits<double>::infinity();
  /// @throws std::invalid_argument naming the field, its value and the allowed range.
  void Validate() const;
};

/// One sample as the state machine sees it.
struct ExperimentSample {
  double level_m = 0.0;
  bool level_valid = false;  ///< read, in range, not stale
  bool link_ok = true;       ///< the PLC answered this poll
  /// When the sample was taken (s, any origin; NaN: unknown, the gap is not checked).
  double time_s = std::numeric_limits<double>::quiet_NaN();
};

enum class ExperimentEventKind : std::uint8_t {
  kStart,  ///< begin (from idle, done or aborted); sample.time_s: the last sample's time (or NaN)
  kStop,   ///< operator stop: abort with kOperatorStop
  kJointStop,  ///< its joint experiment fails (AbortReason::kJointStop): abort with it
  /// Its joint experiment's leader completed its excitation: a running experiment ends done, its
  /// nominal restored, without identification (its record served the leader's).
  kJointEnd,
  kSample,             ///< a new sample
  kWriteFailed,        ///< a setpoint write failed
  kGuardNotPersisted,  ///< the restart guard (core/experiment/experiment_guard.h) could not be
                       ///< persisted
  kIdentificationSucceeded,
  kIdentificationFailed,
};

struct ExperimentEvent {
  ExperimentEventKind kind = ExperimentEventKind::kSample;
  ExperimentSample sample;  ///< for kSample (and its time_s for kStart)
};

/// Mutable state: a value, copied in and out of Step (no allocation; the PRBS register is inside).
struct ExperimentState {
  ExperimentPhase phase = ExperimentPhase::kIdle;
  AbortReason abort_reason = AbortReason::kNone;
  std::int64_t samples_in_phase = 0;
  int invalid_run = 0;
  double setpoint = 0.0;  ///< the last setpoint asked for
  /// Time of the last sample seen while settling or exciting (NaN: none yet).
  double last_sample_time_s = std::numeric_limits<double>::quiet_NaN();
  /// kSampleGap: the offending gap (s; negative when time went back).
  double sample_gap_s = 0.0;
  /// Done by kJointEnd: the joint experiment's leader completed its excitation.
  bool ended_with_joint = false;
  std::optional<PrbsGenerator> prbs;
};

/// What the caller must do after a transition.
struct ExperimentActions {
  std::optional<double> write_setpoint;  ///< write this value to the actuator now
  /// The write above is the nominal setpoint (settling, abort, stop, end of the excitation).
  bool restore_nominal = false;
  bool record_sample = false;         ///< this sample belongs to the experiment record
  bool start_identification = false;  ///< the record is complete: identify it
  bool phase_changed = false;         ///< publish the new state
};

struct ExperimentTransition {
  ExperimentState state;
  ExperimentActions actions;
};

/// Why the experiment was aborted, for logs and experiment_state_t.reason: AbortReasonName, and
/// for kSampleGap "sample gap of X s (bound Y s)" (or "sample time went back by X s").
std::string AbortReasonText(const ExperimentPlan& plan, const ExperimentState& state);

/// The text of experiment_state_t.reason: AbortReasonText when aborted, kEndedWithJoint when
/// done by kJointEnd, else the phase's name.
std::string PhaseReasonText(const ExperimentPlan& plan, const ExperimentState& state);
inline constexpr const char* kEndedWithJoint = "ended with its joint experiment";

/// The experiment's state machine as a pure function: (state, event) -> (state, actions).
/// Safety rules, in this order, on every sample while settling or exciting:
///   link lost -> abort (kLinkLost) and restore nominal;
///   time since the previous sample of this run > max_sample_gap_s, or < 0 -> abort (kSampleGap):
///     the record would have a hole the identification cannot see;
///   invalid level for more than max_invalid_samples in a row -> abort (kSensorInvalid);
///   level outside the band -> abort (kLevelOutOfBand);
/// and on a failed write -> abort (kWriteFailed); on a guard not persisted -> abort
/// (kGuardNotPersisted).  An abort always asks for the nominal setpoint,
/// in the same transition (the caller writes it before the next sample).  While exciting, each
/// sample asks for the next PRBS value and is recorded; the last one ends the excitation with the
/// nominal setpoint and starts the identification.  Start while running is ignored; Stop outside
/// settling/exciting/identifying is ignored; JointEnd outside settling/exciting is ignored (an
/// experiment identifying its own record finishes it).
/// @pre plan.Validate() passed.
ExperimentTransition Step(const ExperimentPlan& plan, const ExperimentState& state,
                          const ExperimentEvent& event);

}  // namespace canalid::core
