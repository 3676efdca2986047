#include "core/reach/reach_controller.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace canalid::core {

ReachController::ReachController(ReachControllerOptions options)
    : options_(std::move(options)), pipeline_(options_.pipeline) {
  if (options_.nominal_setpoint) initial_plan_error_ = SetNominal(*options_.nominal_setpoint);
}

std::string ReachController::SetNominal(double nominal) {
  nominal_ = nominal;
  nominal_known_ = true;
  if (!options_.experiment_for_nominal) return {};
  try {
    pipeline_.SetExperimentPlan(options_.experiment_for_nominal(nominal));
  } catch (const std::invalid_argument& e) {
    // No safe experiment around this nominal: the reach is watched and estimated, never excited.
    return e.what();
  }
  return {};
}

std::string ReachController::ApplyRestart(const RestartDecision& decision) {
  refused_ = !decision.excitation_allowed;
  held_ = decision.hold_until_restored;
  // A decision other than "start as usual" comes from a guard an interrupted run left.
  guard_on_disk_ = decision.action != RestartDecision::Action::kNone;
  keep_guard_ = decision.action == RestartDecision::Action::kRefuse;
  restore_pending_ = decision.restore_setpoint;
  restore_first_write_.reset();
  // Refused without a nominal: the actuator may sit at a PRBS level, so its reading is no nominal.
  adopt_reading_ = !refused_;
  if (decision.nominal) return SetNominal(*decision.nominal);
  return {};
}

ReachPollOutcome ReachController::OnPoll(const ReachReadings& r) {
  ReachPollOutcome outcome;
  if (!nominal_known_ && adopt_reading_ && r.actuator_valid) {
    outcome.nominal_read = r.actuator;
    outcome.plan_error = SetNominal(r.actuator);
  }
  ReachSample sample;
  sample.q_in_valid = r.q_in_valid;
  sample.q_out_valid = r.q_out_valid;
  sample.level_valid = r.level_valid;
  sample.q_in_m3s = r.q_in_m3s;
  sample.q_out_m3s = r.q_out_m3s;
  sample.level_m = r.level_m;
  sample.link_ok = r.link_ok;
  sample.time_s = r.time_s;
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  if (options_.channels.actuator_position >= 0) {
    sample.input = r.actuator_position_valid ? r.actuator_position : kNan;
  } else {
    sample.input = r.actuator_valid ? r.actuator : kNan;
  }
  sample.scheduling = r.scheduling_valid ? r.scheduling : kNan;
  outcome.actions = Track(pipeline_.OnSample(sample));
  if (restore_pending_ && r.link_ok && !outcome.actions.write_setpoint) {
    // Asked again until the PLC confirms it (a write may be lost with the link, or refused).
    outcome.actions.write_setpoint = restore_pending_;
    outcome.actions.restore_nominal = true;
  }
  return outcome;
}

std::optional<ReachActions> ReachController::StartIfDue(bool status_ok, bool allowed) {
  if (!options_.start_experiment_on_start || started_ || !nominal_known_ || !status_ok ||
      !allowed || !excitation_allowed()) {
    return std::nullopt;
  }
  started_ = true;
  return Track(pipeline_.StartExperiment());
}

std::string ReachController::StartRefusal() const {
  if (!pipeline_.experiment_plan()) return "no experiment to start";
  if (!excitation_allowed()) {
    return "experiment refused: an interrupted experiment's nominal is not restored (see the "
           "start-up log)";
  }
  return {};
}

ReachActions ReachController::Start() { return Track(pipeline_.StartExperiment()); }

ReachActions ReachController::Stop() { return Track(pipeline_.StopExperiment()); }

ReachActions ReachController::OnLinkLost() { return Track(pipeline_.OnLinkLost()); }

ReachActions ReachController::OnGuardNotPersisted() {
  return Track(pipeline_.OnGuardNotPersisted());
}

std::optional<IntegratorDelayIdentification> ReachController::IdentifyRecord(
    ReachActions* actions) {
  std::optional<IntegratorDelayIdentification> result = pipeline_.IdentifyRecord(actions);
  *actions = Track(*actions);
  return result;
}

ReachWriteOutcome ReachController::OnWriteResult(const ActuatorWrite& write) {
  ReachWriteOutcome outcome;
  if (!write.written) {
    outcome.actions = Track(pipeline_.OnWriteFailed());
    return outcome;
  }
  // A write asked for before this restore began (say, the previous stop's, answered after an
  // excitation write) says nothing of where the actuator is now.
  if (!restore_pending_ || !restore_first_write_ || write.id < *restore_first_write_ ||
      std::abs(write.value - *restore_pending_) > 1e-9 * (1.0 + std::abs(*restore_pending_))) {
    return outcome;
  }
  restore_pending_.reset();
  restore_first_write_.reset();
  outcome.restore_confirmed = true;
  const ExperimentPhase phase = pipeline_.experiment_state().phase;
  if (phase == ExperimentPhase::kSettling || phase == ExperimentPhase::kExciting) {
    return outcome;  // a new experiment's settling write, not an end: its guard stays
  }
  outcome.remove_guard = guard_on_disk_ && !keep_guard_;
  if (outcome.remove_guard) guard_on_disk_ = false;
  held_ = false;
  return outcome;
}

void ReachController::OnWriteQueued(std::uint64_t id) {
  if (restore_pending_ && !restore_first_write_) restore_first_write_ = id;
}

ReachActions ReachController::Track(ReachActions actions) {
  // A restore is pending until confirmed; an excitation write supersedes it (the experiment's
  // end or abort restores again), so no poll re-asks for the nominal in the middle of one. Each
  // restore begins anew: only writes queued from now on can confirm it.
  if (actions.write_setpoint) {
    restore_pending_ = actions.restore_nominal ? actions.write_setpoint : std::optional<double>();
    restore_first_write_.reset();
  }
  return actions;
}

}  // namespace canalid::core
