#include "core/reach/reach_controller.h"

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
  outcome.actions = pipeline_.OnSample(sample);
  return outcome;
}

std::optional<ReachActions> ReachController::StartIfDue(bool status_ok, bool allowed) {
  if (!options_.start_experiment_on_start || started_ || !nominal_known_ || !status_ok ||
      !allowed || !excitation_allowed()) {
    return std::nullopt;
  }
  started_ = true;
  return pipeline_.StartExperiment();
}

}  // namespace canalid::core
