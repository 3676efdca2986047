#include "core/experiment/experiment.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace canalid::core {
namespace {

ExperimentTransition Abort(const ExperimentPlan& plan, ExperimentState state, AbortReason reason) {
  state.phase = ExperimentPhase::kAborted;
  state.abort_reason = reason;
  state.samples_in_phase = 0;
  state.setpoint = plan.prbs.nominal;
  ExperimentActions actions;
  actions.write_setpoint = plan.prbs.nominal;
  actions.restore_nominal = true;
  actions.phase_changed = true;
  return {state, actions};
}

ExperimentTransition Enter(ExperimentState state, ExperimentPhase phase) {
  state.phase = phase;
  state.samples_in_phase = 0;
  ExperimentActions actions;
  actions.phase_changed = true;
  return {state, actions};
}

// The setpoint of the excitation's current sample (samples_in_phase of exciting): the step's
// level, or the PRBS's next bit.
double ExcitationSetpoint(const ExperimentPlan& plan, ExperimentState& state) {
  if (plan.step_hold_samples > 0) {
    return state.samples_in_phase < plan.step_hold_samples ? plan.prbs.nominal + plan.prbs.amplitude
                                                           : plan.prbs.nominal;
  }
  if (!state.prbs) state.prbs.emplace(plan.prbs);
  return state.prbs->Next();
}

ExperimentTransition OnSample(const ExperimentPlan& plan, ExperimentState state,
                              const ExperimentSample& s) {
  if (!IsRunning(state.phase)) return {state, {}};
  if (!s.link_ok) return Abort(plan, state, AbortReason::kLinkLost);
  if (std::isfinite(s.time_s)) {
    const double gap = s.time_s - state.last_sample_time_s;
    if (std::isfinite(state.last_sample_time_s) && (gap > plan.max_sample_gap_s || gap < 0.0)) {
      state.sample_gap_s = gap;
      return Abort(plan, state, AbortReason::kSampleGap);
    }
    state.last_sample_time_s = s.time_s;
  }
  if (!s.level_valid) {
    if (++state.invalid_run > plan.max_invalid_samples) {
      return Abort(plan, state, AbortReason::kSensorInvalid);
    }
  } else {
    state.invalid_run = 0;
    if (s.level_m < plan.level_min_m || s.level_m > plan.level_max_m) {
      return Abort(plan, state, AbortReason::kLevelOutOfBand);
    }
  }
  if (state.phase == ExperimentPhase::kSettling) {
    if (++state.samples_in_phase < plan.settle_samples) return {state, {}};
    ExperimentTransition t = Enter(state, ExperimentPhase::kExciting);
    t.state.prbs.reset();
    t.state.setpoint = ExcitationSetpoint(plan, t.state);
    t.actions.write_setpoint = t.state.setpoint;
    return t;
  }
  // Exciting: this sample answers the setpoint written after the previous one.
  ExperimentActions actions;
  actions.record_sample = true;
  if (++state.samples_in_phase >= plan.excite_samples) {
    ExperimentTransition t = Enter(state, ExperimentPhase::kIdentifying);
    t.state.setpoint = plan.prbs.nominal;
    t.actions.record_sample = true;
    t.actions.write_setpoint = plan.prbs.nominal;
    t.actions.restore_nominal = true;
    t.actions.start_identification = true;
    return t;
  }
  state.setpoint = ExcitationSetpoint(plan, state);
  actions.write_setpoint = state.setpoint;
  return {state, actions};
}

}  // namespace

const char* ExperimentPhaseName(ExperimentPhase phase) {
  switch (phase) {
    case ExperimentPhase::kIdle:
      return "idle";
    case ExperimentPhase::kSettling:
      return "settling";
    case ExperimentPhase::kExciting:
      return "exciting";
    case ExperimentPhase::kIdentifying:
      return "identifying";
    case ExperimentPhase::kDone:
      return "done";
    case ExperimentPhase::kAborted:
      return "aborted";
  }
  return "unknown";
}

const char* AbortReasonName(AbortReason reason) {
  switch (reason) {
    case AbortReason::kNone:
      return "none";
    case AbortReason::kLevelOutOfBand:
      return "level out of band";
    case AbortReason::kSensorInvalid:
      return "level sensor invalid";
    case AbortReason::kLinkLost:
      return "PLC link lost";
    case AbortReason::kWriteFailed:
      return "setpoint write failed";
    case AbortReason::kOperatorStop:
      return "stopped by operator";
    case AbortReason::kIdentificationFailed:
      return "identification failed";
    case AbortReason::kGuardNotPersisted:
      return "experiment guard not persisted";
    case AbortReason::kSampleGap:
      return "sample gap";
    case AbortReason::kJointStop:
      return "stopped with its joint experiment";
  }
  return "unknown";
}

std::string AbortReasonText(const ExperimentPlan& plan, const ExperimentState& state) {
  if (state.abort_reason != AbortReason::kSampleGap) return AbortReasonName(state.abort_reason);
  char text[96];
  if (state.sample_gap_s < 0.0) {
    std::snprintf(text, sizeof text, "sample time went back by %.3g s", -state.sample_gap_s);
  } else {
    std::snprintf(text, sizeof text, "sample gap of %.3g s (bound %.3g s)", state.sample_gap_s,
                  plan.max_sample_gap_s);
  }
  return text;
}

std::string PhaseReasonText(const ExperimentPlan& plan, const ExperimentState& state) {
  if (state.phase == ExperimentPhase::kAborted) return AbortReasonText(plan, state);
  if (state.phase == ExperimentPhase::kDone && state.ended_with_joint) return kEndedWithJoint;
  return ExperimentPhaseName(state.phase);
}

void ExperimentPlan::Validate() const {
  prbs.Validate();
  if (settle_samples < 0) {
    throw std::invalid_argument("experiment settle_samples must be >= 0 (got " +
                                std::to_string(settle_samples) + ")");
  }
  if (excite_samples < 1) {
    throw std::invalid_argument("experiment excite_samples must be >= 1 (got " +
                                std::to_string(excite_samples) + ")");
  }
  if (step_hold_samples < 0 || (step_hold_samples > 0 && excite_samples != 2 * step_hold_samples)) {
    throw std::invalid_argument("experiment step_hold_samples " +
                                std::to_string(step_hold_samples) +
                                " must be >= 0, and half of excite_samples (" +
                                std::to_string(excite_samples) + ") when > 0");
  }
  if (!(level_max_m > level_min_m)) {
    throw std::invalid_argument("experiment level band: level_max_m (" +
                                std::to_string(level_max_m) + ") must be above level_min_m (" +
                                std::to_string(level_min_m) + ")");
  }
  if (max_invalid_samples < 0) {
    throw std::invalid_argument("experiment max_invalid_samples must be >= 0");
  }
  if (!(max_sample_gap_s > 0.0)) {
    throw std::invalid_argument("experiment max_sample_gap_s must be > 0 (got " +
                                std::to_string(max_sample_gap_s) + ")");
  }
}

ExperimentTransition Step(const ExperimentPlan& plan, const ExperimentState& state,
                          const ExperimentEvent& event) {
  switch (event.kind) {
    case ExperimentEventKind::kStart: {
      if (IsRunning(state.phase) || state.phase == ExperimentPhase::kIdentifying)
        return {state, {}};
      ExperimentState fresh;
      fresh.setpoint = plan.prbs.nominal;
      // The run's first sample must follow the last one before the start within the bound.
      fresh.last_sample_time_s = event.sample.time_s;
      ExperimentTransition t = Enter(fresh, ExperimentPhase::kSettling);
      // Settling starts from the nominal setpoint, whatever the actuator was doing.
      t.actions.write_setpoint = plan.prbs.nominal;
      t.actions.restore_nominal = true;
      if (plan.settle_samples == 0) {
        t.state.phase = ExperimentPhase::kExciting;
        t.state.prbs.reset();
        t.state.setpoint = ExcitationSetpoint(plan, t.state);
        t.actions.write_setpoint = t.state.setpoint;
        t.actions.restore_nominal = false;
      }
      return t;
    }
    case ExperimentEventKind::kStop:
    case ExperimentEventKind::kJointStop:
      if (IsRunning(state.phase) || state.phase == ExperimentPhase::kIdentifying) {
        return Abort(plan, state,
                     event.kind == ExperimentEventKind::kStop ? AbortReason::kOperatorStop
                                                              : AbortReason::kJointStop);
      }
      return {state, {}};
    case ExperimentEventKind::kJointEnd: {
      if (!IsRunning(state.phase)) return {state, {}};
      ExperimentTransition t = Enter(state, ExperimentPhase::kDone);
      t.state.ended_with_joint = true;
      t.state.setpoint = plan.prbs.nominal;
      t.actions.write_setpoint = plan.prbs.nominal;
      t.actions.restore_nominal = true;
      return t;
    }
    case ExperimentEventKind::kSample:
      return OnSample(plan, state, event.sample);
    case ExperimentEventKind::kWriteFailed:
      if (IsRunning(state.phase)) return Abort(plan, state, AbortReason::kWriteFailed);
      return {state, {}};
    case ExperimentEventKind::kGuardNotPersisted:
      if (IsRunning(state.phase)) return Abort(plan, state, AbortReason::kGuardNotPersisted);
      return {state, {}};
    case ExperimentEventKind::kIdentificationSucceeded:
      if (state.phase == ExperimentPhase::kIdentifying) return Enter(state, ExperimentPhase::kDone);
      return {state, {}};
    case ExperimentEventKind::kIdentificationFailed:
      if (state.phase == ExperimentPhase::kIdentifying) {
        ExperimentTransition t = Enter(state, ExperimentPhase::kAborted);
        t.state.abort_reason = AbortReason::kIdentificationFailed;
        return t;
      }
      return {state, {}};
  }
  return {state, {}};
}

}  // namespace canalid::core
