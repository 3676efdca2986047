#include "daemon/canalidd/restore_safety.h"

#include <cmath>
#include <exception>

#include "core/experiment/experiment_guard.h"
#include "daemon/canalidd/clock.h"
#include "daemon/canalidd/log.h"

namespace canalid::daemon {

void ResumeInterruptedExperiment(ReachRuntime& reach, const drivers::PollChannel& channel,
                                 StateStore* store, LcmPublisher& publisher) {
  core::GuardReading reading;
  if (store != nullptr) {
    try {
      reading = store->LoadGuard(reach.name());
    } catch (const std::exception& e) {
      reading.kind = core::GuardReading::Kind::kCorrupt;
      reading.problem = e.what();
    }
  }
  if (reading.kind == core::GuardReading::Kind::kNone) return;
  core::RestartContext context;
  context.reach = reach.name();
  context.actuator = channel.name;
  context.setpoint_min = channel.limits.min_value;
  context.setpoint_max = channel.limits.max_value;
  context.configured_nominal = reach.wiring.runner.nominal_setpoint;
  const core::RestartDecision decision = core::DecideRestart(context, reading);
  (decision.error ? LogError : LogWarning)(decision.message);
  const std::string plan_error = reach.runner.ApplyRestart(decision);
  if (!plan_error.empty()) LogError("reach " + reach.name() + ": no experiment: " + plan_error);
  const bool restore = decision.action == core::RestartDecision::Action::kRestore;
  const std::string reason =
      restore ? std::string(core::kRestartRestoreReason) + " " +
                    std::to_string(*decision.restore_setpoint) + " persisted at " +
                    core::FormatUtcTime(reading.guard.started_utime_us)
              : std::string(core::kRestartRefusedReason) + ": " + decision.message;
  publisher.PublishRestart(reach.name(), channel.name,
                           decision.restore_setpoint ? *decision.restore_setpoint : std::nan(""),
                           reason, WallNowS());
}

bool PersistGuard(ReachRuntime& reach, const std::string& actuator, StateStore* store) {
  const double nominal = reach.runner.nominal();
  const std::string refused = "reach " + reach.name() + ": experiment guard not persisted";
  if (store == nullptr) {
    LogError(refused + " (no state directory): no excitation, restoring nominal " +
             std::to_string(nominal));
    return false;
  }
  core::ExperimentGuard guard;
  guard.reach = reach.name();
  guard.actuator = actuator;
  guard.experiment = reach.runner.experiment_name();
  guard.nominal_setpoint = nominal;
  guard.started_utime_us = ToUtime(WallNowS());
  try {
    // Blocking (write, fsync, rename, fsync of the directory: a few ms), once per experiment, on
    // the loop thread: the excitation write must wait for it, and the poller keeps polling.
    store->SaveGuard(guard);
  } catch (const std::exception& e) {
    LogError(refused + " (" + e.what() + "): no excitation, restoring nominal " +
             std::to_string(nominal));
    return false;
  }
  reach.runner.OnGuardPersisted();
  LogInfo("reach " + reach.name() + ": experiment guard persisted (" + guard.actuator +
          ", nominal " + std::to_string(nominal) + ")");
  return true;
}

void RemoveGuard(const ReachRuntime& reach, StateStore* store) {
  // The controller asks only for a guard written through, or read from, the store.
  if (store == nullptr) return;
  try {
    store->RemoveGuard(reach.name());
  } catch (const std::exception& e) {
    LogError(std::string("state: ") + e.what());
  }
}

}  // namespace canalid::daemon
