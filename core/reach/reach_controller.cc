#include "core/reach/reach_controller.h"

#include <algorithm>
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
  std::string errors;
  plans_.assign(options_.experiments.size(), std::nullopt);
  std::optional<std::size_t> first;
  for (std::size_t i = 0; i < options_.experiments.size(); ++i) {
    const ReachExperiment& experiment = options_.experiments[i];
    try {
      ExperimentPlan plan = experiment.plan_for_nominal(nominal);
      plan.Validate();
      plans_[i] = plan;
      if (!first || experiment.start_on_start) first = i;
    } catch (const std::invalid_argument& e) {
      // No safe plan around this nominal: the experiment cannot run (the reach is still watched
      // and estimated).
      if (!errors.empty()) errors += "; ";
      errors += "experiment '" + experiment.name + "': " + e.what();
    }
  }
  installed_.reset();
  if (first) Install(*first);
  return errors;
}

const std::string& ReachController::experiment_name() const {
  static const std::string kNone;
  return installed_ ? options_.experiments[*installed_].name : kNone;
}

std::optional<std::size_t> ReachController::FindExperiment(std::string_view name,
                                                           std::string* problem) const {
  const auto& all = options_.experiments;
  if (name.empty()) {
    if (all.size() == 1) return 0;
    std::string names;
    for (const ReachExperiment& e : all) names += (names.empty() ? "'" : ", '") + e.name + "'";
    *problem =
        all.empty() ? "no experiment to start" : "name the experiment to start (" + names + ")";
    return std::nullopt;
  }
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].name == name) return i;
  }
  // The name comes from a command: shown with anything unprintable (a newline) as '?'.
  std::string shown(name.substr(0, 64));
  for (char& ch : shown) {
    if (static_cast<unsigned char>(ch) < 0x20 || static_cast<unsigned char>(ch) > 0x7e) ch = '?';
  }
  *problem = "no experiment '" + shown + "' for this reach";
  return std::nullopt;
}

bool ReachController::Install(std::size_t index) {
  if (installed_ == index) return true;
  if (index >= plans_.size() || !plans_[index]) return false;
  if (!pipeline_.SetExperimentPlan(*plans_[index])) return false;
  installed_ = index;
  return true;
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
  if (started_ || !nominal_known_ || !status_ok || !allowed || !excitation_allowed()) {
    return std::nullopt;
  }
  const auto& all = options_.experiments;
  const auto on_start = std::find_if(all.begin(), all.end(),
                                     [](const ReachExperiment& e) { return e.start_on_start; });
  if (on_start == all.end()) return std::nullopt;
  started_ = true;
  if (!Install(static_cast<std::size_t>(on_start - all.begin()))) return std::nullopt;
  return Track(pipeline_.StartExperiment());
}

std::string ReachController::StartRefusal(std::string_view name) const {
  if (refused_) {
    return "refused at start-up: an interrupted experiment's guard needs an operator (check the "
           "actuator, remove the guard, restart; see the start-up log)";
  }
  std::string problem;
  const std::optional<std::size_t> index = FindExperiment(name, &problem);
  if (!index) return problem;
  const std::string& found = options_.experiments[*index].name;
  if (*index >= plans_.size() || !plans_[*index]) {
    return nominal_known_ ? "experiment '" + found +
                                "' has no room around the nominal (see the "
                                "start-up log)"
                          : "experiment '" + found + "' waits for the nominal setpoint";
  }
  if (held_)
    return "an interrupted experiment's nominal is not restored yet (see the start-up log)";
  const ExperimentPhase phase = pipeline_.experiment_state().phase;
  if (IsRunning(phase) || phase == ExperimentPhase::kIdentifying) {
    return "experiment '" + experiment_name() + "' is running";
  }
  return {};
}

ReachActions ReachController::Start(std::string_view name) {
  std::string problem;
  const std::optional<std::size_t> index = FindExperiment(name, &problem);
  if (!index || !Install(*index)) return {};
  return Track(pipeline_.StartExperiment());
}

ReachActions ReachController::Stop() { return Track(pipeline_.StopExperiment()); }

ReachActions ReachController::StopJoint() { return Track(pipeline_.StopJointExperiment()); }

ReachActions ReachController::EndJoint() { return Track(pipeline_.EndJointExperiment()); }

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
  if (IsRunning(pipeline_.experiment_state().phase)) {
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
